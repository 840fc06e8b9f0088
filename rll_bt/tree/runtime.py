"""A loaded, runnable tree: :class:`LoadedTree`.

``tick()`` ticks once; ``run(hz=...)`` ticks on the context clock until the
root succeeds or fails; ``interrupt()`` halts everything that runs (every
running node's ``terminate`` is called, so skills stop the robot).  Tick
observers (the JSON-lines tick log) see every visited node of every tick.
"""
from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import py_trees
from py_trees.common import Status

from .blackboard import ERROR_CODE_KEY, ERROR_MESSAGE_KEY, ERROR_NODE_KEY, Blackboard
from .context import RunContext
from .spec import NodeSpec, TreeSpec


@dataclass
class NodeInfo:
    """One behaviour of a loaded tree, with where it came from."""
    id: int
    parent: int | None
    depth: int
    behaviour: py_trees.behaviour.Behaviour
    spec: NodeSpec | None


@dataclass(frozen=True)
class TreeFailure:
    """Why a tree failed, as left on the blackboard by ``fail_with_error``,
    ``recovery`` or ``timeout``."""
    code: str
    message: str = ""
    node: str = ""


class LoadedTree:
    """A py_trees behaviour tree built from a :class:`TreeSpec`."""

    def __init__(self, root: py_trees.behaviour.Behaviour, ctx: RunContext, spec: TreeSpec | None = None,
                 nodes: list[NodeInfo] | None = None):
        self.root = root
        self.ctx = ctx
        self.spec = spec
        self.nodes = nodes or _index(root)
        self.count = 0
        self._observers: list[Callable[[LoadedTree, list], None]] = []
        self._setup_done = False

    @property
    def blackboard(self) -> Blackboard:
        return self.ctx.blackboard

    @property
    def status(self) -> Status:
        return self.root.status

    @property
    def name(self) -> str:
        return self.spec.name if self.spec else self.root.name

    def setup(self, **kwargs: Any) -> None:
        """Call every behaviour's ``setup`` (once)."""
        if not self._setup_done:
            for info in self.nodes:
                info.behaviour.setup(**kwargs)
            self._setup_done = True

    def add_observer(self, fn: Callable[[LoadedTree, list], None]) -> None:
        """``fn(tree, visited)`` after each tick; ``visited`` lists the
        behaviours ticked, in order."""
        self._observers.append(fn)

    def remove_observer(self, fn) -> None:
        self._observers.remove(fn)

    def tick(self) -> Status:
        """Tick the tree once and return the root's status."""
        if not self._setup_done:
            self.setup()
        self.count += 1
        if self._observers:
            visited = list(self.root.tick())
            for fn in self._observers:
                fn(self, visited)
        else:
            for _ in self.root.tick():
                pass
        return self.root.status

    def run(self, hz: float = 10.0, max_ticks: int | None = None, timeout: float | None = None,
            on_tick: Callable[[LoadedTree], None] | None = None) -> Status:
        """Tick at ``hz`` (context clock) until SUCCESS or FAILURE.  Stops
        (interrupting the tree) after ``max_ticks`` ticks or ``timeout``
        seconds and returns RUNNING then."""
        clock = self.ctx.clock
        period = 1.0 / hz if hz > 0 else 0.0
        start = clock.now()
        ticks = 0
        try:
            while True:
                status = self.tick()
                ticks += 1
                if on_tick is not None:
                    on_tick(self)
                if status in (Status.SUCCESS, Status.FAILURE):
                    return status
                if (max_ticks is not None and ticks >= max_ticks) or \
                        (timeout is not None and clock.now() - start >= timeout):
                    self.interrupt()
                    return Status.RUNNING
                rest = start + ticks * period - clock.now()   # a fixed schedule: no drift
                if rest > 0:
                    clock.sleep(rest)
        except BaseException:
            self.interrupt()
            raise

    def interrupt(self) -> None:
        """Halt every running node (terminate with INVALID)."""
        if self.root.status is not Status.INVALID:
            self.root.stop(Status.INVALID)

    def shutdown(self) -> None:
        self.interrupt()
        for info in self.nodes:
            info.behaviour.shutdown()

    def error(self) -> TreeFailure | None:
        """The error code left by the last failure, or None."""
        code = self.blackboard.get(ERROR_CODE_KEY)
        if code is None:
            return None
        return TreeFailure(str(code), str(self.blackboard.get(ERROR_MESSAGE_KEY) or ""),
                           str(self.blackboard.get(ERROR_NODE_KEY) or ""))

    def outputs(self) -> dict[str, Any]:
        """The values of the keys the tree declares under ``outputs:`` (those
        written so far), by their declared names: what the caller reads."""
        keys = self.spec.output_keys if self.spec is not None else {}
        return {name: self.blackboard.get(key) for name, key in keys.items() if key in self.blackboard}

    def tip(self) -> py_trees.behaviour.Behaviour | None:
        return self.root.tip()

    def find(self, name: str) -> py_trees.behaviour.Behaviour:
        """The first behaviour named ``name`` (KeyError when none)."""
        for info in self.nodes:
            if info.behaviour.name == name:
                return info.behaviour
        raise KeyError(name)

    def as_py_trees(self) -> py_trees.trees.BehaviourTree:
        """A py_trees ``BehaviourTree`` over the same root (for py_trees tools)."""
        return py_trees.trees.BehaviourTree(self.root)


def _index(root) -> list[NodeInfo]:
    out: list[NodeInfo] = []

    def walk(b, parent, depth):
        info = NodeInfo(len(out), parent, depth, b, getattr(b, "spec", None))
        out.append(info)
        for c in b.children:
            walk(c, info.id, depth + 1)
    walk(root, None, 0)
    return out
