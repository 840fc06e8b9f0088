"""Typed ports of node types and the values bound to them.

A node type declares its ports as class attributes::

    class Grab(Node):
        side = Input(str, "which side of the station", choices=("input", "output"))
        timeout = Input(float, "give up after this many seconds", default=20.0)
        holding = Output(bool, "whether a workpiece is in the gripper afterwards")

In the node, ``self.side`` reads the bound value (a literal from the tree
file, or the current blackboard value of the key it is bound to) and
``self.holding = True`` writes the bound blackboard key.  An output that the
tree does not bind is simply not written.
"""
from __future__ import annotations

from collections.abc import Iterable
from typing import Any

from .porttypes import PortType, port_type

MISSING: Any = type("Missing", (), {"__repr__": lambda self: "MISSING", "__bool__": lambda self: False})()


# -- bindings ---------------------------------------------------------------
class Binding:
    """What a port is bound to.  ``source`` is the text in the tree file."""
    __slots__ = ("source",)
    const = False

    def read(self, bb):  # pragma: no cover - abstract
        raise NotImplementedError


class Const(Binding):
    """A value fixed when the tree is loaded (a literal, ``$task.x``, ``$param.x``)."""
    __slots__ = ("value",)
    const = True

    def __init__(self, value: Any, source: str | None = None):
        self.value = value
        self.source = source if source is not None else repr(value)

    def read(self, bb):
        return self.value

    def __repr__(self) -> str:
        return f"Const({self.value!r})"


class Key(Binding):
    """A blackboard key (absolute, e.g. ``/approach/target``)."""
    __slots__ = ("key", "default")

    def __init__(self, key: str, source: str | None = None, default: Any = None):
        self.key = key
        self.default = default
        self.source = source if source is not None else f"$bb.{key}"

    def read(self, bb):
        return bb._data.get(self.key, self.default)

    def with_default(self, default: Any) -> Key:
        return Key(self.key, self.source, default)

    def __repr__(self) -> str:
        return f"Key({self.key!r})"


class Unknown(Binding):
    """A value only known when a task is given (``rll-bt tree validate``)."""
    __slots__ = ("ptype",)

    def __init__(self, ptype: PortType, source: str):
        self.ptype = ptype
        self.source = source

    def read(self, bb):
        raise RuntimeError(f"{self.source} has no value: the tree was loaded without a task")

    def __repr__(self) -> str:
        return f"Unknown({self.source})"


def BB(key: str) -> Key:
    """Bind a port to a blackboard key when building nodes from Python."""
    if not key.startswith("/"):
        key = "/" + key
    return Key(key)


# -- declarations -----------------------------------------------------------
class Port:
    """A declared port.  ``required`` defaults to "no default given" for
    inputs and to False for outputs; ``constant`` ports take only values fixed
    at load time (literals, ``$task``, ``$param``), never ``$bb`` keys."""

    direction = "in"

    def __init__(self, type: Any = object, doc: str = "", *, default: Any = MISSING,
                 required: bool | None = None, choices: Iterable | None = None,
                 constant: bool = False, name: str | None = None):
        self.ptype: PortType = port_type(type)
        self.doc = doc
        self.choices = tuple(choices) if choices is not None else None
        self.constant = constant
        self.name = name or ""
        if self.direction == "out":
            if default is not MISSING:
                raise TypeError("an output port has no default")
            self.required = bool(required)
            self.default = None
        else:
            self.required = (default is MISSING) if required is None else bool(required)
            if default is not MISSING and default is not None:
                default = self.ptype.coerce(default)
            self.default = None if default is MISSING else default
        if self.choices is not None:
            self.choices = tuple(self.ptype.coerce(c) for c in self.choices)

    def __set_name__(self, owner, name: str) -> None:
        if not self.name:
            self.name = name

    def describe(self) -> dict:
        """A JSON-able description (``rll-bt tree nodes --json``)."""
        d = {"name": self.name, "direction": self.direction, "type": self.ptype.name, "doc": self.doc,
             "required": self.required, "constant": self.constant}
        if self.direction == "in" and not self.required:
            d["default"] = self.default
        if self.choices is not None:
            d["choices"] = list(self.choices)
        return d

    def check(self, value: Any) -> Any:
        """Convert a literal for this port or raise ``PortTypeError``."""
        from .porttypes import PortTypeError
        value = self.ptype.coerce(value)
        if self.choices is not None and value not in self.choices:
            raise PortTypeError(f"expected one of {', '.join(map(str, self.choices))}; got {value!r}")
        return value


class Input(Port):
    """An input port: read it as ``self.<name>``."""
    direction = "in"

    def __get__(self, obj, objtype=None):
        if obj is None:
            return self
        return obj._bindings[self.name].read(obj._bb)

    def __set__(self, obj, value) -> None:
        raise AttributeError(f"input port {self.name!r} is read-only; declare an Output to write")


class Output(Port):
    """An output port: ``self.<name> = value`` writes the bound blackboard key."""
    direction = "out"

    def __get__(self, obj, objtype=None):
        if obj is None:
            return self
        b = obj._bindings.get(self.name)
        return None if b is None else b.read(obj._bb)

    def __set__(self, obj, value) -> None:
        b = obj._bindings.get(self.name)
        if b is not None:
            obj._bb.set(b.key, value)


class BoundPorts:
    """The port bindings handed to a node's constructor, with the blackboard
    they read from.  ``get``/``set`` are the non-attribute spelling of
    ``self.<port>``; ``key(name)`` is the absolute blackboard key (or None)."""
    __slots__ = ("bindings", "blackboard")

    def __init__(self, bindings: dict[str, Binding], blackboard):
        self.bindings = bindings
        self.blackboard = blackboard

    def get(self, name: str, default: Any = None) -> Any:
        b = self.bindings.get(name)
        return default if b is None else b.read(self.blackboard)

    def set(self, name: str, value: Any) -> None:
        b = self.bindings.get(name)
        if isinstance(b, Key):
            self.blackboard.set(b.key, value)

    def key(self, name: str) -> str | None:
        b = self.bindings.get(name)
        return b.key if isinstance(b, Key) else None

    def is_bound(self, name: str) -> bool:
        return name in self.bindings

    def __repr__(self) -> str:
        return f"BoundPorts({self.bindings!r})"
