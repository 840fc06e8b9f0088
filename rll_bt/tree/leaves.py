"""Generic leaf node types: wait, log, blackboard set/unset/check/wait-for,
success/failure/running, fail_with_error, clear_error and stop_robot."""
from __future__ import annotations

import logging

from py_trees.common import Status

from .blackboard import clear_error, write_error
from .node import Node
from .ports import Input, Key, Output
from .porttypes import EXPR, type_of_value
from .registry import node_type

_LEVELS = {"debug": logging.DEBUG, "info": logging.INFO, "warning": logging.WARNING, "error": logging.ERROR}


@node_type("wait")
class Wait(Node):
    """Wait ``seconds`` of the context clock (RUNNING until then), then SUCCESS."""
    seconds = Input(float, "how long to wait, in seconds")
    preempts = True

    def initialise(self) -> None:
        s = self.seconds
        self._until = None if s is None else self.ctx.clock.now() + max(0.0, float(s))

    def update(self) -> Status:
        if self._until is None:
            self.feedback_message = f"no value for seconds ({self.bound.key('seconds')} is not set)"
            return Status.FAILURE
        return Status.SUCCESS if self.ctx.clock.now() >= self._until else Status.RUNNING


@node_type("log")
class Log(Node):
    """Log ``message`` (and ``value``, when bound) at ``level``; SUCCESS."""
    message = Input(str, "the text to log")
    value = Input(object, "a value to log with the message (often $bb.KEY)", required=False)
    level = Input(str, "log level", default="info", choices=tuple(_LEVELS), constant=True)
    preempts = False

    def update(self) -> Status:
        text = self.message if "value" not in self.bound.bindings else f"{self.message}: {self.value!r}"
        self.log.log(_LEVELS[self.level], "%s", text)
        self.feedback_message = text
        return Status.SUCCESS


@node_type("set_blackboard")
class SetBlackboard(Node):
    """Write ``value`` to the blackboard ``key``; SUCCESS."""
    key = Output(object, "where to write ($bb.KEY)", required=True)
    value = Input(object, "what to write: a literal, $task.NAME, $param.NAME or $bb.KEY (copied)")
    preempts = False

    @classmethod
    def infer_output_types(cls, spec):
        b = spec.ports.get("value")
        return {"key": type_of_value(b.value)} if b is not None and b.const else {}

    def update(self) -> Status:
        self.key = self.value
        return Status.SUCCESS


@node_type("unset_blackboard")
class UnsetBlackboard(Node):
    """Remove the blackboard ``key`` (if present); SUCCESS."""
    key = Output(object, "the key to remove ($bb.KEY)", required=True)
    preempts = False

    def update(self) -> Status:
        k = self.bound.key("key")
        if k is not None:
            self._bb.unset(k)
        return Status.SUCCESS


class _ExprNode(Node):
    """Shared by the nodes that test a condition expression."""
    condition = Input(EXPR, "the condition expression", constant=True)

    def __init__(self, name, ports, ctx):
        super().__init__(name, ports, ctx)
        self._fn = self.condition.bind(self._bb)


@node_type("check_blackboard")
class CheckBlackboard(_ExprNode):
    """SUCCESS when ``condition`` holds, else FAILURE.  The condition is an
    expression over blackboard keys such as ``"holding == true and attempts < 3"``."""
    kind = "condition"

    def update(self) -> Status:
        return Status.SUCCESS if self._fn() else Status.FAILURE


@node_type("wait_for_blackboard")
class WaitForBlackboard(_ExprNode):
    """RUNNING until ``condition`` holds, then SUCCESS (wrap in ``timeout`` to bound it)."""
    preempts = False

    def update(self) -> Status:
        return Status.SUCCESS if self._fn() else Status.RUNNING


@node_type("success")
class Success(Node):
    """Always SUCCESS."""
    kind = "condition"

    def update(self) -> Status:
        return Status.SUCCESS


@node_type("failure")
class Failure(Node):
    """Always FAILURE."""
    kind = "condition"

    def update(self) -> Status:
        return Status.FAILURE


@node_type("running")
class Running(Node):
    """Always RUNNING (a placeholder for work that never ends by itself)."""
    preempts = False

    def update(self) -> Status:
        return Status.RUNNING


@node_type("fail_with_error")
class FailWithError(Node):
    """Write an error ``code`` and ``message`` for the agent to report
    (``/error/code``, ``/error/message``, ``/error/node``) and FAIL."""
    code = Input(str, "the error code, e.g. GRASP_FAILED (the agent maps it to the team protocol)")
    message = Input(str, "what went wrong, for people", default="")
    preempts = False

    def update(self) -> Status:
        write_error(self._bb, self.code, self.message, self.name)
        self.feedback_message = f"{self.code}: {self.message}"
        return Status.FAILURE


@node_type("clear_error")
class ClearError(Node):
    """Remove the error code and message written by an earlier failure; SUCCESS."""
    preempts = False

    def update(self) -> Status:
        clear_error(self._bb)
        return Status.SUCCESS


@node_type("stop_robot")
class StopRobot(Node):
    """Stop the robot base at once (``backend.stop()``); SUCCESS.  FAILURE
    when the run context has no backend."""

    def update(self) -> Status:
        backend = self.ctx.backend
        if backend is None:
            self.feedback_message = "no backend"
            return Status.FAILURE
        backend.stop()
        return Status.SUCCESS


__all__ = ["Wait", "Log", "SetBlackboard", "UnsetBlackboard", "CheckBlackboard", "WaitForBlackboard", "Success",
           "Failure", "Running", "FailWithError", "ClearError", "StopRobot", "Key"]
