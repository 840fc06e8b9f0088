"""The ``recovery`` node: an action with ordered, escalating recoveries.

In the manner of Nav2's RecoveryNode with a RoundRobin of recoveries: when
the action fails, recovery level 1 runs and the action is tried again; if it
fails again (``retries`` rounds per level), level 2 runs, and so on.  What a
recovery that itself fails does is the node's ``on_recovery_failure``:
``escalate`` (the default) goes on at once to the next level without trying
the action again; ``retry`` counts the round as done and tries the action
again anyway (BT.CPP's ForceSuccess around the recovery: the code reported
at the end is the action's own); ``fail`` fails the node at once (Nav2's
RecoveryNode).  When the last level is used up the node fails and, with
``error_code``, writes the code and a message to the blackboard
(``/error/code``, ``/error/message``) for the agent to report.  At most one
child is ticked per tick, so a chain of instant failures cannot spin inside
one tick.
"""
from __future__ import annotations

from collections.abc import Iterator

import py_trees
from py_trees.common import Status

from .blackboard import clear_error, write_error
from .ports import Input, Output
from .registry import DEFAULT, Slot, structural

_R, _S, _F, _I = Status.RUNNING, Status.SUCCESS, Status.FAILURE, Status.INVALID

#: what a failed recovery does (``on_recovery_failure``)
POLICIES = ("escalate", "retry", "fail")


class Recovery(py_trees.composites.Composite):
    """children[0] is the action, children[1:] the recovery levels in order."""

    def __init__(self, name: str, action: py_trees.behaviour.Behaviour,
                 recoveries: list[py_trees.behaviour.Behaviour], retries: int = 1,
                 blackboard=None, error_code: str | None = None, error_message: str | None = None,
                 level_key: str | None = None, on_recovery_failure: str = "escalate"):
        super().__init__(name, [action, *recoveries])
        if retries < 1:
            raise ValueError("retries must be at least 1")
        if on_recovery_failure not in POLICIES:
            raise ValueError(f"on_recovery_failure must be one of {', '.join(POLICIES)}")
        self.on_recovery_failure = on_recovery_failure
        self.action = action
        self.recoveries = list(recoveries)
        self.retries = retries
        self.bb = blackboard
        self.error_code, self.error_message = error_code, error_message
        self.level_key = level_key
        self.level = 0          # 0: the first try; k: after recovery level k
        self.round = 0
        self._phase = "action"
        self.history: list[str] = []     # what ran, for logs and tests

    def _set_level(self, level: int, round_: int) -> None:
        self.level, self.round = level, round_
        if self.level_key is not None and self.bb is not None:
            self.bb.set(self.level_key, level)

    def initialise(self) -> None:
        self._set_level(0, 0)
        self._phase = "action"
        self.history = []

    def _escalate(self) -> bool:
        """Choose the next recovery; False when none is left."""
        if self.level > 0 and self.round < self.retries:
            self._set_level(self.level, self.round + 1)
        else:
            self._set_level(self.level + 1, 1)
        if self.level > len(self.recoveries):
            return False
        self._phase = "recover"
        return True

    def _fail(self, why: str | None = None) -> None:
        self.feedback_message = why or (f"{self.action.name} still failing after {len(self.recoveries)} recovery "
                                        f"level(s) x {self.retries}")
        if self.error_code and self.bb is not None:
            write_error(self.bb, self.error_code, self.error_message or self.feedback_message, self.name)
        self.stop(_F)

    def tick(self) -> Iterator[py_trees.behaviour.Behaviour]:
        if self.status is not _R:
            self.initialise()
        if self._phase == "action":
            self.current_child = self.action
            if self.action.status is not _R:
                self.history.append(f"action@{self.level}")
            yield from self.action.tick()
            st = self.action.status
            if st is _S:
                if self.level > 0 and self.bb is not None:
                    clear_error(self.bb)
                self.stop(_S)
            elif st is _F:
                self._after_failure()
            else:
                self.status = _R
        else:
            rec = self.recoveries[self.level - 1]
            self.current_child = rec
            if rec.status is not _R:
                self.history.append(f"recovery{self.level}.{self.round}")
            yield from rec.tick()
            st = rec.status
            if st is _S or (st is _F and self.on_recovery_failure == "retry"):
                self._phase = "action"          # the round is done: try the action again
                self.status = _R
            elif st is _F and self.on_recovery_failure == "fail":
                self._fail(f"recovery level {self.level} ({rec.name}) failed")
            elif st is _F:
                self.round = self.retries      # escalate: on to the next level at once
                self._after_failure()
            else:
                self.status = _R
        yield self

    def _after_failure(self) -> None:
        if self._escalate():
            self.status = _R
        else:
            self._fail()

    def stop(self, new_status: Status = _I) -> None:
        for child in self.children:
            if child.status is _R:
                child.stop(_I)
        super().stop(new_status)


def _build(spec, slots, ctx):
    lk = spec.ports.get("level")
    return Recovery(spec.name, slots["action"][0], slots["recoveries"], spec.const("retries"), ctx.blackboard,
                    spec.const("error_code"), spec.const("error_message"), lk.key if lk is not None else None,
                    spec.const("on_recovery_failure"))


def _check(spec, opts):
    r = spec.const("retries")
    if r is not None and r < 1:
        return [(opts.vloc("retries"), f"`retries` must be at least 1, got {r}", "retries counts the rounds "
                 "of (recovery, try again) per level")]
    return []


DEFAULT.register(structural(
    "recovery", "composite", "Make an action succeed with ordered, escalating recoveries.\n\n"
    + __doc__.split("\n\n", 1)[1],
    (Input(int, "rounds of (recovery, try the action again) per level", default=1, constant=True,
           name="retries"),
     Input(str, "error code written when every level is used up", required=False, constant=True,
           name="error_code"),
     Input(str, "message written with the error code", required=False, constant=True, name="error_message"),
     Input(str, "what a recovery that fails does: escalate (next level at once), retry (try the action "
           "again anyway) or fail (the node fails)", default="escalate", choices=POLICIES, constant=True,
           name="on_recovery_failure"),
     Output(int, "the recovery level in use (0 before any recovery)", name="level")),
    (Slot("action", doc="the node to make succeed"),
     Slot("recoveries", many=True, doc="recovery nodes, mildest first")),
    _build, _check))
