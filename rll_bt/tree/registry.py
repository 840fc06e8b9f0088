"""The node registry: which node types a tree file may use.

Leaf types are :class:`~rll_bt.tree.node.Node` subclasses registered with
the :func:`node_type` decorator (or :func:`register`).  Structural types
(composites, decorators, ``recovery``, ``subtree``) are
:class:`StructuralType` objects whose children sit in named slots.

Third-party packages add node types through the ``rll_bt.nodes`` entry
point group; the entry point may name a module (importing it registers its
types with ``@node_type``), a function ``f(registry)``, or a Node subclass.
"""
from __future__ import annotations

import importlib
import inspect
import logging
import threading
from collections.abc import Callable, Iterable
from dataclasses import dataclass
from typing import Any

from .node import Node, _snake
from .ports import Port

log = logging.getLogger(__name__)

BUILTIN_MODULES = ("rll_bt.tree.composites", "rll_bt.tree.decorators", "rll_bt.tree.recovery", "rll_bt.tree.subtree",
                   "rll_bt.tree.leaves")


@dataclass(frozen=True)
class Slot:
    """Where a structural node keeps children: ``many`` (a list) or one node.
    ``expr`` lets a one-node slot take a condition expression instead."""
    name: str
    many: bool = False
    required: bool = True
    expr: bool = False
    doc: str = ""


@dataclass
class NodeType:
    """A registered node type as the loader, the CLI and the schema see it."""
    name: str
    kind: str                       # action | condition | composite | decorator | subtree
    doc: str
    ports: dict[str, Port]
    slots: tuple[Slot, ...] = ()
    cls: type | None = None         # Node subclass for leaves
    build: Callable | None = None   # structural: build(spec, slots, ctx) -> Behaviour
    module: str = ""
    check: Callable | None = None   # structural: extra load-time check(spec, report)

    @property
    def summary(self) -> str:
        """The first sentence of the documentation."""
        para = self.doc.strip().split("\n\n")[0].replace("\n", " ") if self.doc else ""
        head, dot, _ = para.partition(". ")
        return head + "." if dot else para

    def describe(self) -> dict[str, Any]:
        return {"name": self.name, "kind": self.kind, "doc": inspect.cleandoc(self.doc or ""),
                "module": self.module, "ports": [p.describe() for p in self.ports.values()],
                "slots": [{"name": s.name, "many": s.many, "required": s.required, "expression": s.expr,
                           "doc": s.doc} for s in self.slots]}


def structural(name: str, kind: str, doc: str, ports: Iterable[Port], slots: Iterable[Slot],
               build: Callable, check: Callable | None = None) -> NodeType:
    """Describe a composite or decorator type (``ports`` must be named)."""
    pmap = {}
    for p in ports:
        if not p.name:
            raise ValueError(f"{name}: structural ports need names")
        pmap[p.name] = p
    return NodeType(name, kind, inspect.cleandoc(doc), pmap, tuple(slots), None, build,
                    getattr(build, "__module__", ""), check)


class NodeRegistry:
    """Node types by name.  ``child()`` layers a registry over this one (a
    test or a team can add types without touching the default)."""

    def __init__(self, parent: NodeRegistry | None = None):
        self._types: dict[str, NodeType] = {}
        self._parent = parent

    def register(self, cls_or_type, name: str | None = None, *, replace: bool = False) -> NodeType:
        """Register a Node subclass (under ``name``, default its snake-case
        class name) or a :class:`NodeType`."""
        if isinstance(cls_or_type, NodeType):
            nt = cls_or_type
        elif isinstance(cls_or_type, type) and issubclass(cls_or_type, Node):
            cls = cls_or_type
            tname = name or cls.__dict__.get("node_type") or _snake(cls.__name__)
            if not cls.__doc__ or not cls.__doc__.strip():
                raise TypeError(f"node type {tname!r} ({cls.__name__}) needs a docstring: it is its documentation")
            if not cls.__dict__.get("node_type"):
                cls.node_type = tname
            nt = NodeType(tname, cls.kind, inspect.cleandoc(cls.__doc__), dict(cls.ports), (), cls, None,
                          cls.__module__)
        else:
            raise TypeError(f"cannot register {cls_or_type!r}: expected a rll_bt.tree.Node subclass")
        if not nt.name.replace("_", "").isalnum() or not nt.name[0].isalpha() or nt.name != nt.name.lower():
            raise ValueError(f"node type name {nt.name!r} must be lower_snake_case")
        old = self._types.get(nt.name)
        if old is not None and not replace and (old.cls is None or old.cls is not nt.cls):
            raise ValueError(f"node type {nt.name!r} is already registered (by {old.module}); "
                             "pass replace=True to override")
        self._types[nt.name] = nt
        return nt

    def get(self, name: str) -> NodeType | None:
        nt = self._types.get(name)
        if nt is None and self._parent is not None:
            return self._parent.get(name)
        return nt

    def __contains__(self, name: str) -> bool:
        return self.get(name) is not None

    def types(self) -> dict[str, NodeType]:
        out = dict(self._parent.types()) if self._parent is not None else {}
        out.update(self._types)
        return dict(sorted(out.items()))

    def names(self) -> list[str]:
        return list(self.types())

    def child(self) -> NodeRegistry:
        return NodeRegistry(self)


#: the process-wide registry; builtins and plug-ins are added on first use
DEFAULT = NodeRegistry()
_loaded = False
_lock = threading.Lock()


def node_type(name: str | None = None, *, registry: NodeRegistry | None = None, replace: bool = False):
    """Class decorator registering a Node subclass::

        @node_type("grab")
        class Grab(Node):
            \"\"\"Grab a workpiece ...\"\"\"
    """
    def deco(cls):
        (registry or DEFAULT).register(cls, name, replace=replace)
        return cls
    if isinstance(name, type):      # used bare: @node_type
        cls, name = name, None
        return deco(cls)
    return deco


def register(cls_or_type, name: str | None = None, *, registry: NodeRegistry | None = None,
             replace: bool = False) -> NodeType:
    """Function form of :func:`node_type`."""
    return (registry or DEFAULT).register(cls_or_type, name, replace=replace)


def default_registry() -> NodeRegistry:
    """The default registry with the built-in types and every ``rll_bt.nodes`` plug-in."""
    global _loaded
    if _loaded:
        return DEFAULT
    with _lock:
        if _loaded:
            return DEFAULT
        for mod in BUILTIN_MODULES:
            importlib.import_module(mod)
        from .. import plugins
        for ep_name, obj in plugins.load_all("rll_bt.nodes").items():
            try:
                if inspect.ismodule(obj):
                    continue            # importing it registered its types
                if isinstance(obj, type) and issubclass(obj, Node):
                    DEFAULT.register(obj, obj.__dict__.get("node_type") or ep_name)
                elif callable(obj):
                    obj(DEFAULT)
                else:
                    log.warning("rll_bt.nodes entry point %r is neither a module, a Node nor a function", ep_name)
            except Exception as exc:    # a broken plug-in must not take the engine down
                log.warning("cannot register nodes from rll_bt.nodes entry point %r: %s", ep_name, exc)
        _loaded = True
    return DEFAULT
