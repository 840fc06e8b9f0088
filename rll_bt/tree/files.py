"""Tree files as the loader reads them, and their instances.

A :class:`TreeFile` is one file's header: its name and the declarations of
its task fields (``task:``), parameters (``params:``), the keys it writes
for its caller (``outputs:``) and its own blackboard keys
(``blackboard:``).  An :class:`Instance` is one use of a file in a tree
(the root file, or one ``subtree`` node): its blackboard scope, its
parameter values and how its keys map to its caller's.
"""
from __future__ import annotations

import os
import re
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from .errors import Loc, did_you_mean
from .ports import Binding
from .porttypes import PortTypeError, port_type, type_names
from .source import YMap
from .spec import Decl

HEADER_KEYS = ("name", "doc", "task", "params", "outputs", "blackboard", "root")
DECL_KEYS = ("type", "doc", "default", "required", "choices")
SEGMENT = re.compile(r"[A-Za-z_][A-Za-z0-9_]*$")

Report = Callable[[Loc, str, str], None]


@dataclass
class TreeFile:
    path: Path
    display: str
    doc: YMap | None
    name: str = ""
    task: dict[str, Decl] = field(default_factory=dict)
    params: dict[str, Decl] = field(default_factory=dict)
    outputs: dict[str, Decl] = field(default_factory=dict)
    blackboard: dict[str, Decl] = field(default_factory=dict)


@dataclass
class Instance:
    """One instance of one file: its scope, parameters and remapping."""
    file: TreeFile
    scope: str
    params: dict[str, Binding]
    remap: dict[str, str]
    autoremap: bool
    parent: Instance | None
    stack: tuple[Path, ...]

    def key(self, name: str) -> str:
        """The absolute blackboard key of ``name`` written in this instance."""
        if name.startswith("/"):
            return name
        if name in self.remap:
            return self.remap[name]
        if self.autoremap and self.parent is not None:
            return self.parent.key(name)
        return self.scope + name


def display(path: Path) -> str:
    """``path`` as error messages show it: relative to the working directory when inside it."""
    try:
        rel = os.path.relpath(path)
    except ValueError:
        return str(path)
    return rel if not rel.startswith("..") else str(path)


def valid_key(name: str) -> bool:
    body = name[1:] if name.startswith("/") else name
    return bool(body) and all(SEGMENT.match(s) and not s.startswith("__") for s in body.split("/"))


class CliText(str):
    """A value typed on the command line: converted to the declared type."""
    from_cli = True


def check_value(decl: Decl, value: Any) -> Any:
    """``value`` converted to ``decl``'s type and checked against its choices
    (raises :class:`PortTypeError`)."""
    if value is None:
        return None
    if isinstance(value, str) and decl.ptype.name not in ("str", "expr", "any") and getattr(value, "from_cli", False):
        value = decl.ptype.from_text(value)
    v = decl.ptype.coerce(value)
    if decl.choices and v not in decl.choices:
        raise PortTypeError(f"expected one of {', '.join(map(str, decl.choices))}; got {v!r}")
    return v


def read_decls(doc: YMap, section: str, report: Report, keys: bool = False) -> dict[str, Decl]:
    """The declarations under ``section`` (``task``, ``params``, ``outputs``
    or ``blackboard``; ``keys``: names may be blackboard keys with ``/``)."""
    out: dict[str, Decl] = {}
    if section not in doc or doc[section] is None:
        return out
    block = doc[section]
    if not isinstance(block, YMap):
        report(doc.vloc(section), f"`{section}:` must map names to types",
               f"e.g. {section}:\n    zone: {{type: str, doc: \"zone to explore\"}}")
        return out
    for name, spec in block.items():
        loc = block.kloc(name)
        if not isinstance(name, str) or not (valid_key(name) if keys else SEGMENT.match(name)):
            report(loc, f"{name!r} is not a valid {'key' if keys else 'name'}",
                   "use letters, digits and '_' (keys may use '/' between parts)")
            continue
        if isinstance(spec, str):
            spec_map: dict = {"type": spec}
            vlocs = {"type": block.vloc(name)}
        elif isinstance(spec, YMap):
            spec_map, vlocs = spec, {k: spec.vloc(k) for k in spec}
            for k in spec:
                if k not in DECL_KEYS:
                    report(spec.kloc(k), f"unknown field {k!r} in the declaration of {name!r}",
                           did_you_mean(str(k), DECL_KEYS, "fields"))
        else:
            report(block.vloc(name), f"declaration of {name!r} must be a type name or a mapping",
                   "e.g. `zone: str` or `zone: {type: str, default: C_Z11}`")
            continue
        tname = spec_map.get("type", "any")
        try:
            ptype = port_type(str(tname))
        except (KeyError, TypeError):
            report(vlocs.get("type", loc), f"unknown type {tname!r}", did_you_mean(str(tname), type_names(), "types"))
            continue
        has_default = "default" in spec_map
        if section == "outputs" and (has_default or "required" in spec_map):
            report(vlocs.get("default", vlocs.get("required", loc)), f"output {name!r} takes no default or "
                   "`required`", "an output is written by the tree; give it `type` and `doc`")
            has_default = False
        required = spec_map.get("required", not has_default and not keys and section != "outputs")
        if not isinstance(required, bool):
            report(vlocs.get("required", loc), "`required` must be true or false", "")
            required = True
        choices = spec_map.get("choices")
        if choices is not None and not isinstance(choices, list):
            report(vlocs.get("choices", loc), "`choices` must be a list", "e.g. choices: [input, output]")
            choices = None
        decl = Decl(name, ptype, None, required, str(spec_map.get("doc", "") or ""),
                    tuple(choices) if choices else None, loc)
        if has_default and spec_map["default"] is not None:
            try:
                decl.default = check_value(decl, spec_map["default"])
            except PortTypeError as exc:
                report(vlocs.get("default", loc), f"default of {name!r}: {exc}", f"give a {ptype.name} default")
        out[name] = decl
    return out
