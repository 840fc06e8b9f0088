"""JSON Schema of the tree format, for editor completion and checking.

The shipped file ``rll_bt/tree/schema/tree.schema.json`` covers the
built-in node types; ``rll-bt tree schema`` writes one that also covers
every installed plug-in's node types.  In an editor with a YAML language
server, put this first line in a tree file::

    # yaml-language-server: $schema=<path to tree.schema.json>
"""
from __future__ import annotations

import json
from pathlib import Path

from .ports import Port
from .porttypes import type_names
from .registry import NodeRegistry, NodeType, default_registry

SHIPPED = Path(__file__).with_name("schema") / "tree.schema.json"
_REF_ANY = {"type": "string", "pattern": r"^\$(task|param|bb)\.", "description": "$task.NAME, $param.NAME or $bb.KEY"}
_REF_CONST = {"type": "string", "pattern": r"^\$(task|param)\.", "description": "$task.NAME or $param.NAME"}
_REF_BB = {"type": "string", "pattern": r"^\$bb\.", "description": "a blackboard key: $bb.KEY"}
_NODE = {"$ref": "#/$defs/node"}


def _port(p: Port) -> dict:
    if p.direction == "out":
        return dict(_REF_BB, description=p.doc)
    base = dict(p.ptype.schema)
    if p.choices is not None:
        base["enum"] = list(p.choices)
    return {"anyOf": [base, _REF_CONST if p.constant else _REF_ANY], "description": p.doc
            + ("" if p.required else f" (default: {json.dumps(p.default)})")}


def _node_type(nt: NodeType) -> tuple[dict, bool]:
    props: dict = {"name": {"type": "string", "description": "the node's name (shown in logs)"}}
    required: list[str] = []
    for name, p in nt.ports.items():
        props[name] = _port(p)
        if p.required:
            required.append(name)
    many_slot = None
    if nt.kind != "subtree":
        for s in nt.slots:
            if s.many:
                props[s.name] = {"type": "array", "items": _NODE, "description": s.doc}
                many_slot = many_slot or s.name
            elif s.expr:
                props[s.name] = {"anyOf": [_NODE, {"type": "string"}], "description": s.doc}
            else:
                props[s.name] = dict(_NODE)
            if s.required:
                required.append(s.name)
    if nt.kind == "subtree":
        props["params"] = {"type": "object", "description": nt.ports["params"].doc}
        props["remap"] = {"type": "object", "additionalProperties": _REF_BB, "description": nt.ports["remap"].doc}
        props["pass"] = {"anyOf": [{"const": "all"}, {"type": "array", "items": {"type": "string"}}],
                         "description": nt.ports["pass"].doc}
    options: dict = {"type": "object", "properties": props, "additionalProperties": False}
    if required:
        options["required"] = required
    alts = [options]
    if many_slot is not None:
        alts.append({"type": "array", "items": _NODE, "description": f"shorthand for {many_slot}:"})
    if not required:
        alts.append({"type": "null"})
    entry = {"type": "object", "properties": {nt.name: {"anyOf": alts} if len(alts) > 1 else options},
             "required": [nt.name], "additionalProperties": False, "description": nt.summary}
    return entry, not required


def tree_schema(registry: NodeRegistry | None = None, builtin_only: bool = False) -> dict:
    """The JSON Schema (draft 2020-12) of tree files for ``registry``."""
    reg = registry or default_registry()
    entries, bare = [], []
    for name, nt in reg.types().items():
        if builtin_only and not nt.module.startswith("rll_bt.tree"):
            continue
        entry, can_be_bare = _node_type(nt)
        entries.append(entry)
        if can_be_bare and nt.kind in ("action", "condition"):
            bare.append(name)
    decl = {"anyOf": [
        {"type": "string", "enum": type_names() + ["list[...]", "dict[...]"]},
        {"type": "object", "additionalProperties": False, "properties": {
            "type": {"type": "string", "description": "a port type name, e.g. str, int, float, pose, list[str]"},
            "doc": {"type": "string"}, "default": {}, "required": {"type": "boolean"},
            "choices": {"type": "array"}}}]}
    return {
        "$schema": "https://json-schema.org/draft/2020-12/schema",
        "$id": "https://rll-bt.invalid/schema/tree.schema.json",
        "title": "rll-bt behaviour tree",
        "description": "A behaviour tree for rll-bt; see docs/trees.md",
        "type": "object",
        "properties": {
            "name": {"type": "string", "description": "the tree's name (default: the file name)"},
            "doc": {"type": "string", "description": "what the tree does"},
            "task": {"type": "object", "additionalProperties": {"$ref": "#/$defs/decl"},
                     "description": "task fields this file uses as $task.NAME"},
            "params": {"type": "object", "additionalProperties": {"$ref": "#/$defs/decl"},
                       "description": "parameters ($param.NAME), given by the including subtree node"},
            "outputs": {"type": "object", "additionalProperties": {"$ref": "#/$defs/decl"},
                        "description": "keys this file writes for its caller (the caller's keys of the same "
                                       "name unless its subtree node remaps them); each must be written"},
            "blackboard": {"type": "object", "additionalProperties": {"$ref": "#/$defs/decl"},
                           "description": "blackboard keys of this file with types and initial values"},
            "root": _NODE,
        },
        "required": ["root"],
        "additionalProperties": False,
        "$defs": {"node": {"anyOf": [{"type": "string", "enum": sorted(bare)}, *entries]}, "decl": decl},
    }


def schema_text(registry: NodeRegistry | None = None, builtin_only: bool = False) -> str:
    return json.dumps(tree_schema(registry, builtin_only), indent=1, sort_keys=False) + "\n"
