"""One task's tree, from loading to its outcome: :class:`TaskRun`.

The tree of a task kind is ``<trees_dir>/<kind>.yaml``, loaded with the
task's parameters as ``$task.NAME`` and a fresh blackboard, sharing the
agent's services.  ``tick()`` ticks it once and keeps track of the time it
has run (pauses do not count against the task's timeout); ``halt()``
interrupts it (every running node's ``terminate`` stops what it
commanded) so that the next tick starts again from the root, with the
blackboard kept; ``cancel()`` halts it for good.
"""
from __future__ import annotations

import importlib.util
import logging
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from py_trees.common import Status

from ..backend import SensorLost
from ..clock import Clock
from ..tree import Blackboard, LoadedTree, RunContext, TreeLoadError, load_tree
from ..tree.recovery import Recovery

log = logging.getLogger("rll_bt.agent")


class InvalidTask(ValueError):
    """A task the agent cannot run as given: no tree for it, or the tree does not load."""


def default_trees_dir() -> Path | None:
    """The ``trees/`` package installed with rll-bt (found, not imported):
    beside the ``rll_bt`` package, else wherever the import system finds a
    regular ``trees`` package (a stray ``trees/`` folder in the working
    directory does not count)."""
    beside = Path(__file__).resolve().parents[2] / "trees"
    if (beside / "__init__.py").is_file():
        return beside
    spec = importlib.util.find_spec("trees")
    if spec is None or spec.origin is None or not spec.submodule_search_locations:
        return None
    return Path(list(spec.submodule_search_locations)[0])


def tree_file(trees_dir: Path, kind: str) -> Path:
    return trees_dir / f"{kind}.yaml"


def load_task_tree(trees_dir: Path, kind: str, params: dict[str, Any], *, backend, clock: Clock,
                   services: dict[str, Any], registry=None, logger: logging.Logger | None = None) -> LoadedTree:
    """Build the tree for a task and make the services its nodes require;
    :class:`InvalidTask` when there is no tree, it does not load for these
    parameters or a service cannot be made."""
    path = tree_file(trees_dir, kind)
    if not path.is_file():
        raise InvalidTask(f"no tree for {kind!r} tasks ({path} not found)")
    ctx = RunContext(backend=backend, clock=clock, task=params, logger=logger or logging.getLogger("rll_bt.tree"),
                     services=services, blackboard=Blackboard())
    try:
        tree = load_tree(path, task=params, ctx=ctx, registry=registry, search_path=[trees_dir])
    except TreeLoadError as exc:
        raise InvalidTask(f"{path.name} does not load for this task: {exc}") from None
    # make the services the nodes use now, so they have the machine map before the first tick
    for name in sorted({s for info in tree.nodes for s in getattr(info.behaviour, "requires_services", ())}):
        try:
            tree.ctx.service(name)
        except Exception as exc:
            raise InvalidTask(f"{path.name}: service {name!r} cannot be made: {exc}") from None
    return tree


@dataclass
class Outcome:
    status: str            # "SUCCEEDED" / "FAILED" / "CANCELLED"
    code: str = "NONE"     # a tree error code (see errorcodes)
    text: str = ""


class TaskRun:
    """The tree of one task and how far it got."""

    def __init__(self, task, params: dict[str, Any], tree: LoadedTree, clock: Clock, max_gap: float = 0.5):
        self.task = task
        self.task_id = int(task.task_id)
        self.kind = params["kind"]
        self.params = params
        self.tree = tree
        self.clock = clock
        self.timeout = float(params.get("timeout") or 0.0)
        self.max_gap = max_gap            # longest gap between ticks counted as running time
        self.started = clock.now()
        self.active_time = 0.0
        self._last_tick: float | None = None
        self.outcome: Outcome | None = None
        self.ticks = 0
        self.halts = 0

    @property
    def done(self) -> bool:
        return self.outcome is not None

    @property
    def recovering(self) -> bool:
        """A recovery branch is running (a ``recovery`` node above level 0)."""
        for info in self.tree.nodes:
            b = info.behaviour
            if isinstance(b, Recovery) and b.status is Status.RUNNING and b.level > 0:
                return True
        return False

    def tick(self) -> Outcome | None:
        """Tick once; the outcome once the tree has finished (or timed out)."""
        if self.outcome is not None:
            return self.outcome
        now = self.clock.now()
        if self._last_tick is not None:
            self.active_time += min(max(0.0, now - self._last_tick), self.max_gap)
        self._last_tick = now
        if self.timeout and self.active_time >= self.timeout:
            self.halt()
            self.outcome = Outcome("FAILED", "TIMEOUT", f"task took longer than {self.timeout:g} s")
            return self.outcome
        self.ticks += 1
        try:
            status = self.tree.tick()
        except SensorLost as exc:  # the laser or camera went away (the backend stopped the robot)
            log.warning("task %d (%s): %s", self.task_id, self.kind, exc)
            self.halt()
            self.outcome = Outcome("FAILED", "SENSOR_LOST", str(exc))
            return self.outcome
        except Exception as exc:   # a bug in a node: report it, never crash the agent
            log.exception("task %d (%s): the tree raised", self.task_id, self.kind)
            self.halt()
            self.outcome = Outcome("FAILED", "INTERNAL", f"{type(exc).__name__}: {exc}")
            return self.outcome
        if status is Status.SUCCESS:
            self.outcome = Outcome("SUCCEEDED")
        elif status is Status.FAILURE:
            err = self.tree.error()
            if err is None:
                self.outcome = Outcome("FAILED", "INTERNAL", f"{self.tree.name} failed without an error code")
            else:
                self.outcome = Outcome("FAILED", err.code, err.message)
        return self.outcome

    def halt(self) -> None:
        """Interrupt the tree (running nodes terminate and stop the robot);
        the next tick starts at the root again."""
        self._last_tick = None
        if self.tree.status is Status.RUNNING:
            self.halts += 1
        try:
            self.tree.interrupt()
        except Exception:
            log.exception("task %d: halting the tree raised", self.task_id)

    def abandon(self, code: str, text: str) -> Outcome:
        """Stop the task here (halted as by :meth:`halt`): it ends FAILED with ``code``."""
        self.halt()
        self.outcome = Outcome("FAILED", code, text)
        return self.outcome

    def cancel(self, reason: str = "") -> Outcome:
        self.halt()
        self.outcome = Outcome("CANCELLED", "CANCELLED", reason or "cancelled by the team server")
        return self.outcome
