"""The base class of every leaf node type: :class:`Node`.

A node type is a py_trees behaviour with declared, typed ports
(:class:`~rll_bt.tree.ports.Input`, :class:`~rll_bt.tree.ports.Output`), a
docstring (shown by ``rll-bt tree nodes``) and a constructor that receives
its name, its bound ports and the :class:`~rll_bt.tree.context.RunContext`.

Skills never block a tick: ``initialise`` starts the work (sends a command,
starts a planner), ``update`` polls and returns RUNNING, SUCCESS or FAILURE,
``terminate(new_status)`` stops whatever is still going when the node is
interrupted (``new_status`` is INVALID then).

Halt before start: when a node whose ``preempts`` is true (every action by
default) is about to start inside one branch of a selector while another
branch of that selector is RUNNING, the running branch is halted *first*
(terminate is called on it), so a higher-priority branch taking over never
commands the robot while the old one still does, not even for part of a
tick (BehaviorTree.CPP #1031 halts the old branch only afterwards).  In a
``reactive_sequence`` the children before the running one are re-ticked
every tick; they should be conditions or instant nodes (a child there that
returns RUNNING halts the later running child right after it starts, as in
py_trees).
"""
from __future__ import annotations

import re
from collections.abc import Iterator
from typing import Any, ClassVar

import py_trees
from py_trees.common import Status

from ..backend import Capability
from .context import RunContext
from .ports import MISSING, Binding, BoundPorts, Const, Key, Port

_VALID = frozenset(Status)
_RUNNING = Status.RUNNING
_INVALID = Status.INVALID

#: names a port may not take (attributes of behaviours and nodes)
RESERVED = frozenset(dir(py_trees.behaviour.Behaviour)) | {
    "name", "status", "iterator", "parent", "children", "logger", "feedback_message", "blackbox_level",
    "id", "qualified_name", "blackboards", "ctx", "ports", "log", "kind", "preempts", "child", "type",
    "doc", "node_type", "bound", "requires_services", "requires_capabilities", "_bindings", "_bb"}


def _snake(name: str) -> str:
    return re.sub(r"(?<!^)(?=[A-Z])", "_", name).lower()


class Node(py_trees.behaviour.Behaviour):
    """Base class of leaf node types (actions and conditions).

    Class attributes a node type may set:

    - ``kind``: ``"action"`` (may return RUNNING) or ``"condition"``
      (answers SUCCESS/FAILURE at once and changes nothing)
    - ``preempts``: halt abandoned running branches before starting
      (default: true for actions, false for conditions)
    - ``requires_services``: names in ``ctx.services`` it uses, checked at load
    - ``requires_capabilities``: backend capabilities it uses, checked at load
    """

    kind: ClassVar[str] = "action"
    preempts: ClassVar[bool | None] = None
    requires_services: ClassVar[tuple[str, ...]] = ()
    requires_capabilities: ClassVar[Capability] = Capability.NONE
    node_type: ClassVar[str] = ""
    _preempts: ClassVar[bool] = True
    ports: ClassVar[dict[str, Port]] = {}

    def __init_subclass__(cls, **kw) -> None:
        super().__init_subclass__(**kw)
        ports: dict[str, Port] = {}
        for klass in reversed(cls.__mro__):
            for attr, value in vars(klass).items():
                if isinstance(value, Port):
                    ports[value.name or attr] = value
        for pname in ports:
            if pname in RESERVED or pname.startswith("_"):
                raise TypeError(f"{cls.__name__}: port name {pname!r} is reserved; choose another name")
        cls.ports = ports
        if cls.kind not in ("action", "condition"):
            raise TypeError(f"{cls.__name__}: kind must be 'action' or 'condition', not {cls.kind!r}")
        explicit = next((k.__dict__["preempts"] for k in cls.__mro__
                         if k.__dict__.get("preempts") is not None), None)
        cls._preempts = (cls.kind == "action") if explicit is None else bool(explicit)

    def __init__(self, name: str, ports: BoundPorts, ctx: RunContext):
        super().__init__(name)
        self.ctx = ctx
        self.bound = ports
        self._bb = ports.blackboard
        bindings: dict[str, Binding] = {}
        for pname, port in type(self).ports.items():
            b = ports.bindings.get(pname)
            if b is None:
                if port.direction == "in":
                    bindings[pname] = Const(port.default, "default")
            elif isinstance(b, Key) and port.direction == "in" and port.default is not None:
                bindings[pname] = b.with_default(port.default)
            else:
                bindings[pname] = b
        self._bindings = bindings
        self.log = ctx.logger

    # -- building from Python -------------------------------------------------
    @classmethod
    def make(cls, ctx: RunContext | None = None, name: str | None = None, **values: Any) -> Node:
        """Build a node from Python (tests, hand-built trees).  ``values`` are
        literals or :func:`~rll_bt.tree.ports.BB` keys."""
        ctx = ctx or RunContext()
        bindings: dict[str, Binding] = {}
        for pname, value in values.items():
            port = cls.ports.get(pname)
            if port is None:
                raise TypeError(f"{cls.__name__} has no port {pname!r} (ports: {', '.join(cls.ports) or 'none'})")
            if isinstance(value, Binding):
                bindings[pname] = value
            elif port.direction == "out":
                raise TypeError(f"output port {pname!r} needs a blackboard key: BB('key')")
            elif port.ptype.name == "expr":
                from .expr import parse_expr
                bindings[pname] = Const(parse_expr(value), value)
            else:
                bindings[pname] = Const(port.check(value))
        for pname, port in cls.ports.items():
            if port.required and pname not in bindings:
                raise TypeError(f"{cls.__name__} needs port {pname!r}")
        return cls(name or cls.node_type or _snake(cls.__name__), BoundPorts(bindings, ctx.blackboard), ctx)

    # -- ticking ----------------------------------------------------------------
    def tick(self) -> Iterator[py_trees.behaviour.Behaviour]:
        """py_trees' tick contract, plus halt-before-start for preempting nodes."""
        if self.status is not _RUNNING:
            if self._preempts:
                self.halt_abandoned_branches()
            self.initialise()
        new_status = self.update()
        if new_status not in _VALID:
            self.logger.error(f"invalid status {new_status!r} from {self.name}; using INVALID")
            new_status = _INVALID
        if new_status is not _RUNNING:
            self.stop(new_status)
        self.status = new_status
        yield self

    def halt_abandoned_branches(self) -> None:
        """Before this node starts: under every selector above it, halt a
        RUNNING child other than the one leading here (the branch the
        selector is switching away from).  Sequences never have a running
        child after the one being ticked, and parallels run children together."""
        child: py_trees.behaviour.Behaviour = self
        parent = self.parent
        while parent is not None:
            if isinstance(parent, py_trees.composites.Selector) or getattr(parent, "exclusive_children", False):
                for sibling in parent.children:
                    if sibling is not child and sibling.status is _RUNNING:
                        sibling.stop(_INVALID)
            child, parent = parent, parent.parent

    def update(self) -> Status:  # pragma: no cover - subclasses implement
        return Status.SUCCESS

    @classmethod
    def describe(cls) -> dict[str, Any]:
        return {"kind": cls.kind, "ports": [p.describe() for p in cls.ports.values()]}


__all__ = ["Node", "Status", "MISSING"]
