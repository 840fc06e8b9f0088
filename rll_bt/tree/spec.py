"""The checked form of a tree file, before any behaviour is made.

``rll-bt tree validate`` and ``show`` stop here; ``run`` and the agent turn
a :class:`TreeSpec` into py_trees behaviours (:mod:`rll_bt.tree.build`).
"""
from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass, field
from typing import Any

from .errors import Loc
from .ports import Binding
from .porttypes import PortType


@dataclass
class Decl:
    """A declared task field, tree parameter or blackboard key."""
    name: str
    ptype: PortType
    default: Any = None
    required: bool = False
    doc: str = ""
    choices: tuple | None = None
    loc: Loc | None = None

    def describe(self) -> dict:
        d = {"name": self.name, "type": self.ptype.name, "doc": self.doc, "required": self.required}
        if not self.required:
            d["default"] = self.default
        if self.choices:
            d["choices"] = list(self.choices)
        return d


@dataclass
class NodeSpec:
    """One node: its registered type, name, where it was written, its bound
    ports, its children by slot, and the blackboard scope it lives in."""
    type: str
    name: str
    loc: Loc
    kind: str
    ports: dict[str, Binding] = field(default_factory=dict)
    slots: dict[str, list[NodeSpec]] = field(default_factory=dict)
    scope: str = "/"
    file: str | None = None          # for subtrees: the file included
    nodetype: Any = field(default=None, repr=False, compare=False)

    def children(self) -> list[NodeSpec]:
        out: list[NodeSpec] = []
        for specs in self.slots.values():
            out.extend(specs)
        return out

    def walk(self, depth: int = 0) -> Iterator[tuple[int, NodeSpec]]:
        yield depth, self
        for c in self.children():
            yield from c.walk(depth + 1)

    def const(self, port: str, default: Any = None) -> Any:
        """The load-time value of ``port``, or its declared default."""
        b = self.ports.get(port)
        if b is None:
            decl = self.nodetype.ports.get(port) if self.nodetype is not None else None
            return decl.default if decl is not None and decl.default is not None else default
        return getattr(b, "value", default)


@dataclass
class TreeSpec:
    """A whole tree: the root file's header and the root node."""
    file: str
    name: str
    doc: str
    root: NodeSpec
    task: dict[str, Decl]
    params: dict[str, Decl]
    blackboard_init: dict[str, Any]
    key_types: dict[str, PortType]
    files: list[str]
    #: the keys the tree writes for its caller (``outputs:``) and their absolute keys
    outputs: dict[str, Decl] = field(default_factory=dict)
    output_keys: dict[str, str] = field(default_factory=dict)

    def count(self) -> int:
        return sum(1 for _ in self.root.walk())
