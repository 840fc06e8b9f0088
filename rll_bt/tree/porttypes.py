"""Port types: how a YAML literal is checked and converted for a port.

A port is declared with a Python type (``int``, ``float``, ``str``, ``bool``,
``list``, ``dict``, ``object`` for any, :class:`~rll_bt.backend.Pose2D`,
``list[int]`` ...) or a type name (``"int"``, ``"pose"``, ``"expr"``).
Skill authors add their own with :func:`register_type`.  Every type has a
name (shown by ``rll-bt tree nodes`` and used in ``task:``/``params:``
declarations) and a JSON Schema fragment for editor completion.
"""
from __future__ import annotations

import math
import typing
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import yaml

from ..backend.types import Pose2D


class PortTypeError(TypeError):
    """A value does not fit a port type; the message says what was expected."""


@dataclass(frozen=True)
class PortType:
    name: str
    coerce: Callable[[Any], Any] = field(compare=False)
    schema: dict = field(compare=False, default_factory=dict)
    pytype: Any = field(compare=False, default=object)
    literal: bool = True            # can be written as a YAML literal

    def __str__(self) -> str:
        return self.name

    def accepts(self, other: PortType) -> bool:
        """Whether a value of type ``other`` (a writer) may feed this port."""
        if self.name == "any" or other.name == "any" or self.name == other.name:
            return True
        if self.name == "float" and other.name == "int":
            return True
        if self.name == "list" and other.name.startswith("list["):
            return True
        return self.name == "dict" and other.name.startswith("dict[")

    def from_text(self, text: str) -> Any:
        """Convert a command-line string (``--task zone=C_Z12``)."""
        if self.name in ("str", "expr"):
            return self.coerce(text)
        try:
            value = yaml.safe_load(text)
        except yaml.YAMLError:
            value = text
        return self.coerce(value)


def _describe(value: Any) -> str:
    text = repr(value)
    if len(text) > 40:
        text = text[:37] + "..."
    return f"{type(value).__name__} {text}"


def _c_any(v):
    return v


def _c_bool(v):
    if isinstance(v, bool):
        return v
    raise PortTypeError(f"expected bool (true/false), got {_describe(v)}")


def _c_int(v):
    if isinstance(v, int) and not isinstance(v, bool):
        return v
    if isinstance(v, float) and v.is_integer():
        return int(v)
    raise PortTypeError(f"expected int, got {_describe(v)}")


def _c_float(v):
    if isinstance(v, (int, float)) and not isinstance(v, bool):
        f = float(v)
        if math.isnan(f):
            raise PortTypeError("expected a number, got NaN")
        return f
    raise PortTypeError(f"expected float, got {_describe(v)}")


def _c_str(v):
    if isinstance(v, str):
        return v
    raise PortTypeError(f"expected str, got {_describe(v)}")


def _c_list(v):
    if isinstance(v, (list, tuple)):
        return list(v)
    raise PortTypeError(f"expected list, got {_describe(v)}")


def _c_dict(v):
    if isinstance(v, dict):
        return dict(v)
    raise PortTypeError(f"expected dict (a mapping), got {_describe(v)}")


def _c_pose(v):
    if isinstance(v, Pose2D):
        return v
    if isinstance(v, dict) and set(v) <= {"x", "y", "theta"} and v:
        try:
            return Pose2D(*(_c_float(v.get(k, 0.0)) for k in ("x", "y", "theta")))
        except PortTypeError as exc:
            raise PortTypeError(f"pose fields must be numbers: {exc}") from None
    if isinstance(v, (list, tuple)) and len(v) in (2, 3):
        return Pose2D(*(_c_float(x) for x in v))
    raise PortTypeError(f"expected a pose ({{x: m, y: m, theta: rad}} or [x, y, theta]), got {_describe(v)}")


_NUM = {"type": "number"}
ANY = PortType("any", _c_any, {}, object)
BOOL = PortType("bool", _c_bool, {"type": "boolean"}, bool)
INT = PortType("int", _c_int, {"type": "integer"}, int)
FLOAT = PortType("float", _c_float, _NUM, float)
STR = PortType("str", _c_str, {"type": "string"}, str)
LIST = PortType("list", _c_list, {"type": "array"}, list)
DICT = PortType("dict", _c_dict, {"type": "object"}, dict)
POSE = PortType("pose", _c_pose, {"anyOf": [
    {"type": "object", "properties": {"x": _NUM, "y": _NUM, "theta": _NUM}, "additionalProperties": False},
    {"type": "array", "items": _NUM, "minItems": 2, "maxItems": 3}]}, Pose2D)
#: a condition in the safe expression language (see :mod:`rll_bt.tree.expr`)
EXPR = PortType("expr", _c_str, {"type": "string"}, str)

_BY_NAME: dict[str, PortType] = {t.name: t for t in (ANY, BOOL, INT, FLOAT, STR, LIST, DICT, POSE, EXPR)}
_BY_PY: dict[Any, PortType] = {object: ANY, typing.Any: ANY, bool: BOOL, int: INT, float: FLOAT, str: STR,
                               list: LIST, dict: DICT, Pose2D: POSE}


def register_type(name: str, pytype: Any, coerce: Callable[[Any], Any] | None = None,
                  schema: dict | None = None) -> PortType:
    """Add a port type.  ``coerce(value)`` converts a YAML literal or raises
    :class:`PortTypeError`; without it the type cannot be written as a
    literal and only accepts instances of ``pytype`` (from the blackboard)."""
    if name in _BY_NAME:
        raise ValueError(f"port type {name!r} is already registered")
    literal = coerce is not None
    if coerce is None:
        def coerce(v, _t=pytype, _n=name):
            if isinstance(v, _t):
                return v
            raise PortTypeError(f"expected {_n}, got {_describe(v)}")
    t = PortType(name, coerce, schema or {}, pytype, literal)
    _BY_NAME[name] = t
    _BY_PY[pytype] = t
    return t


def _container(kind: str, item: PortType) -> PortType:
    """``list[item]`` or ``dict[item]`` (text keys)."""
    name = f"{kind}[{item.name}]"
    if name not in _BY_NAME:
        def coerce(v, _i=item):
            try:
                if kind == "list":
                    return [_i.coerce(x) for x in _c_list(v)]
                return {str(k): _i.coerce(x) for k, x in _c_dict(v).items()}
            except PortTypeError as exc:
                raise PortTypeError(f"{name} element: {exc}") from None
        schema = ({"type": "array", "items": item.schema} if kind == "list"
                  else {"type": "object", "additionalProperties": item.schema})
        _BY_NAME[name] = PortType(name, coerce, schema, list if kind == "list" else dict, item.literal)
    return _BY_NAME[name]


def port_type(spec: Any) -> PortType:
    """The :class:`PortType` for a Python type, a generic (``list[int]``) or a name."""
    if isinstance(spec, PortType):
        return spec
    if isinstance(spec, str):
        s = spec.strip()
        if s in _BY_NAME:
            return _BY_NAME[s]
        for kind in ("list", "dict"):
            if s.startswith(kind + "[") and s.endswith("]"):
                return _container(kind, port_type(s[len(kind) + 1:-1]))
        raise KeyError(s)
    if spec in _BY_PY:
        return _BY_PY[spec]
    origin = typing.get_origin(spec)
    args = typing.get_args(spec)
    if origin is list and len(args) == 1:
        return _container("list", port_type(args[0]))
    if origin is dict and len(args) == 2 and args[0] is str:
        return _container("dict", port_type(args[1]))
    if isinstance(spec, type):
        return register_type(spec.__name__, spec)
    raise TypeError(f"cannot use {spec!r} as a port type")


def type_names() -> list[str]:
    return sorted(_BY_NAME)


def type_of_value(value: Any) -> PortType:
    """The narrowest built-in type of a literal (for typing blackboard keys)."""
    for t in (BOOL, INT, FLOAT, STR):
        if type(value) is t.pytype:
            return t
    if isinstance(value, Pose2D):
        return POSE
    if isinstance(value, list):
        return LIST
    if isinstance(value, dict):
        return DICT
    return ANY
