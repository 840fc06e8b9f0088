"""Tree files to :class:`~rll_bt.tree.spec.TreeSpec`: parse, resolve, check.

Every problem is collected as a :class:`~rll_bt.tree.errors.Diagnostic`
with ``file:line:column`` and a hint; if any was found,
:class:`~rll_bt.tree.errors.TreeLoadError` lists them all.  Nothing in a
tree file is ever executed: node types must be registered, conditions are
parsed by :mod:`rll_bt.tree.expr`, and YAML is read with ``safe_load``
semantics (:mod:`rll_bt.tree.source`).
"""
from __future__ import annotations

import os
import re
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from .errors import Diagnostic, Loc, TreeLoadError, did_you_mean
from .expr import ExprError, parse_expr
from .ports import Binding, Const, Input, Key, Port, Unknown
from .porttypes import EXPR, PortType, PortTypeError, port_type, type_names
from .registry import NodeRegistry, NodeType, default_registry
from .source import SourceError, YList, YMap, parse_yaml
from .spec import Decl, NodeSpec, TreeSpec

HEADER_KEYS = ("name", "doc", "task", "params", "blackboard", "root")
DECL_KEYS = ("type", "doc", "default", "required", "choices")
_SEGMENT = re.compile(r"[A-Za-z_][A-Za-z0-9_]*$")
_AMBIGUOUS = {
    "sequence": "say whether it remembers: `sequence_with_memory` (resume at the running child) "
                "or `reactive_sequence` (re-check from the first child every tick)",
    "selector": "say whether it remembers: `selector_with_memory` (resume at the running child) "
                "or `reactive_selector` (re-try higher priorities every tick)",
    "fallback": "fallbacks are selectors: use `selector_with_memory` or `reactive_selector`",
}


@dataclass
class _File:
    path: Path
    display: str
    doc: YMap | None
    name: str = ""
    task: dict[str, Decl] = field(default_factory=dict)
    params: dict[str, Decl] = field(default_factory=dict)
    blackboard: dict[str, Decl] = field(default_factory=dict)


@dataclass
class _Env:
    """One instance of one file: its scope, parameters and remapping."""
    file: _File
    scope: str
    params: dict[str, Binding]
    remap: dict[str, str]
    autoremap: bool
    parent: _Env | None
    stack: tuple[Path, ...]

    def key(self, name: str) -> str:
        if name.startswith("/"):
            return name
        if name in self.remap:
            return self.remap[name]
        if self.autoremap and self.parent is not None:
            return self.parent.key(name)
        return self.scope + name


def _display(path: Path) -> str:
    try:
        rel = os.path.relpath(path)
    except ValueError:
        return str(path)
    return rel if not rel.startswith("..") else str(path)


def valid_key(name: str) -> bool:
    body = name[1:] if name.startswith("/") else name
    return bool(body) and all(_SEGMENT.match(s) and not s.startswith("__") for s in body.split("/"))


class Loader:
    """Resolves one root tree file.  ``task=None`` checks without a task
    (``$task.x`` stays symbolic); ``strict`` demands every required task field
    and parameter."""

    def __init__(self, registry: NodeRegistry | None = None, task: Mapping[str, Any] | None = None,
                 params: Mapping[str, Any] | None = None, search_path: Iterable[str | Path] = (),
                 strict: bool = False):
        self.registry = registry or default_registry()
        self.task = None if task is None else dict(task)
        self.root_params = dict(params or {})
        self.search_path = [Path(p) for p in search_path]
        self.strict = strict
        self.diags: list[Diagnostic] = []
        self._files: dict[Path, _File | None] = {}
        self._task_values: dict[tuple[Path, str], Binding] = {}
        self._scope_names: dict[str, set[str]] = {}
        self._reads: list[tuple[str, PortType, Loc, str]] = []
        self._writes: list[tuple[str, PortType, Loc, str]] = []
        self._bb_init: dict[str, Any] = {}
        self._files_used: list[str] = []

    # -- reporting -------------------------------------------------------------
    def error(self, loc: Loc, message: str, hint: str = "") -> None:
        self.diags.append(Diagnostic(loc, message, hint))

    # -- entry -----------------------------------------------------------------
    def load(self, path: str | Path, text: str | None = None) -> TreeSpec:
        p = Path(path)
        f = self._read(p.resolve() if text is None else p, text, display=str(path))
        if f is None:
            raise TreeLoadError(self.diags)
        loc0 = Loc(f.display, 1, 1)
        params: dict[str, Binding] = {}
        for k, v in self.root_params.items():
            decl = f.params.get(k)
            if decl is None:
                self.error(loc0, f"the tree has no parameter {k!r}",
                           did_you_mean(k, f.params, "parameters") or "declare it under `params:`")
                continue
            try:
                params[k] = Const(_check_decl(decl, v), f"$param.{k}")
            except PortTypeError as exc:
                self.error(decl.loc or loc0, f"parameter {k!r}: {exc}", f"give {k} a {decl.ptype.name}")
        for k, decl in f.params.items():
            if k not in params:
                if decl.required:
                    if self.strict:
                        self.error(decl.loc or loc0, f"required parameter {k!r} was not given",
                                   f"pass it: --param {k}=VALUE")
                    params[k] = Unknown(decl.ptype, f"$param.{k}")
                else:
                    params[k] = Const(decl.default, f"$param.{k}")
        env = _Env(f, "/", params, {}, False, None, (f.path,))
        self._init_blackboard(f, env)
        root = self._root_node(f, env)
        self._check_key_types()
        if self.diags or root is None:
            raise TreeLoadError(self.diags or [Diagnostic(loc0, "the tree has no root", "add `root:`")])
        key_types = {}
        for key, t, _loc, _what in self._writes:
            key_types.setdefault(key, t)
        return TreeSpec(f.display, f.name, (f.doc or {}).get("doc", "") or "", root, f.task, f.params,
                        dict(self._bb_init), key_types, list(dict.fromkeys(self._files_used)))

    # -- files -----------------------------------------------------------------
    def _read(self, path: Path, text: str | None = None, display: str | None = None) -> _File | None:
        if path in self._files:
            return self._files[path]
        disp = display or _display(path)
        self._files[path] = None
        if text is None:
            try:
                text = path.read_text(encoding="utf-8")
            except FileNotFoundError:
                self.error(Loc(disp, 1, 1), "file not found", "check the path")
                return None
            except (OSError, UnicodeDecodeError) as exc:
                self.error(Loc(disp, 1, 1), f"cannot read the file: {exc}", "check the file and its permissions")
                return None
        try:
            doc = parse_yaml(text, disp)
        except SourceError as exc:
            self.diags.append(exc.diagnostic)
            return None
        loc0 = Loc(disp, 1, 1)
        if doc is None:
            self.error(loc0, "the file is empty", "a tree file has at least `root:` with one node")
            return None
        if not isinstance(doc, YMap):
            self.error(getattr(doc, "loc", loc0), "a tree file is a mapping with `root:` (and optionally "
                       "name, doc, task, params, blackboard)", "start the file with `root:`")
            return None
        f = _File(path, disp, doc, name=str(doc.get("name") or path.stem))
        for k in doc:
            if k not in HEADER_KEYS:
                self.error(doc.kloc(k), f"unknown top-level key {k!r}",
                           did_you_mean(str(k), HEADER_KEYS, "top-level keys"))
        for k in ("name", "doc"):
            if k in doc and not isinstance(doc[k], str):
                self.error(doc.vloc(k), f"`{k}` must be text", f"write {k}: \"...\"")
        if "root" not in doc:
            self.error(loc0, "the tree has no `root:`", "add `root:` with the top node of the tree")
        f.task = self._decls(doc, "task")
        f.params = self._decls(doc, "params")
        f.blackboard = self._decls(doc, "blackboard", keys=True)
        self._files[path] = f
        self._files_used.append(disp)
        return f

    def _decls(self, doc: YMap, section: str, keys: bool = False) -> dict[str, Decl]:
        out: dict[str, Decl] = {}
        if section not in doc or doc[section] is None:
            return out
        block = doc[section]
        if not isinstance(block, YMap):
            self.error(doc.vloc(section), f"`{section}:` must map names to types",
                       f"e.g. {section}:\n    zone: {{type: str, doc: \"zone to explore\"}}")
            return out
        for name, spec in block.items():
            loc = block.kloc(name)
            if not isinstance(name, str) or not (valid_key(name) if keys else _SEGMENT.match(name)):
                self.error(loc, f"{name!r} is not a valid {'key' if keys else 'name'}",
                           "use letters, digits and '_' (keys may use '/' between parts)")
                continue
            if isinstance(spec, str):
                spec_map: dict = {"type": spec}
                sloc = block.vloc(name)
                vlocs = {"type": sloc}
            elif isinstance(spec, YMap):
                spec_map, vlocs = spec, {k: spec.vloc(k) for k in spec}
                for k in spec:
                    if k not in DECL_KEYS:
                        self.error(spec.kloc(k), f"unknown field {k!r} in the declaration of {name!r}",
                                   did_you_mean(str(k), DECL_KEYS, "fields"))
            else:
                self.error(block.vloc(name), f"declaration of {name!r} must be a type name or a mapping",
                           "e.g. `zone: str` or `zone: {type: str, default: C_Z11}`")
                continue
            tname = spec_map.get("type", "any")
            try:
                ptype = port_type(str(tname))
            except (KeyError, TypeError):
                self.error(vlocs.get("type", loc), f"unknown type {tname!r}",
                           did_you_mean(str(tname), type_names(), "types"))
                continue
            has_default = "default" in spec_map
            required = spec_map.get("required", not has_default and not keys)
            if not isinstance(required, bool):
                self.error(vlocs.get("required", loc), "`required` must be true or false", "")
                required = True
            choices = spec_map.get("choices")
            if choices is not None and not isinstance(choices, list):
                self.error(vlocs.get("choices", loc), "`choices` must be a list", "e.g. choices: [input, output]")
                choices = None
            decl = Decl(name, ptype, None, required, str(spec_map.get("doc", "") or ""),
                        tuple(choices) if choices else None, loc)
            if has_default and spec_map["default"] is not None:
                try:
                    decl.default = _check_decl(decl, spec_map["default"])
                except PortTypeError as exc:
                    self.error(vlocs.get("default", loc), f"default of {name!r}: {exc}",
                               f"give a {ptype.name} default")
            out[name] = decl
        return out

    # -- task values -------------------------------------------------------------
    def _task_binding(self, f: _File, name: str, decl: Decl, text: str) -> Binding:
        cache_key = (f.path, name)
        if cache_key in self._task_values:
            return self._task_values[cache_key]
        if self.task is None:
            b: Binding = Unknown(decl.ptype, text)
        elif name in self.task:
            try:
                b = Const(_check_decl(decl, self.task[name]), text)
            except PortTypeError as exc:
                self.error(decl.loc, f"task field {name!r}: {exc}",
                           f"the task must give {name} as {decl.ptype.name}")
                b = Unknown(decl.ptype, text)
        elif decl.required:
            if self.strict:
                self.error(decl.loc, f"the task does not give the required field {name!r}",
                           f"pass it: --task {name}=VALUE (or give it a default)")
            b = Unknown(decl.ptype, text)
        else:
            b = Const(decl.default, text)
        self._task_values[cache_key] = b
        return b

    # -- references ------------------------------------------------------------
    def _ref(self, text: str, loc: Loc, env: _Env) -> Binding | None:
        kind, _, rest = text[1:].partition(".")
        if kind == "task":
            decl = env.file.task.get(rest)
            if decl is None:
                self.error(loc, f"unknown task field {rest!r} in {text}",
                           (did_you_mean(rest, env.file.task, "task fields") + "; " if env.file.task else "")
                           + f"declare it: task: {{{rest}: {{type: str}}}}")
                return None
            return self._task_binding(env.file, rest, decl, text)
        if kind == "param":
            if rest not in env.file.params:
                self.error(loc, f"unknown parameter {rest!r} in {text}",
                           (did_you_mean(rest, env.file.params, "parameters") + "; " if env.file.params else "")
                           + f"declare it: params: {{{rest}: {{type: str}}}}")
                return None
            return env.params.get(rest, Unknown(env.file.params[rest].ptype, text))
        if kind == "bb":
            if not valid_key(rest):
                self.error(loc, f"{rest!r} is not a valid blackboard key",
                           "keys are names of letters, digits and '_', joined by '/'; a leading '/' is absolute")
                return None
            return Key(env.key(rest), text)
        self.error(loc, f"unknown reference {text!r}",
                   "use $task.NAME, $param.NAME or $bb.KEY; write $$ for a text that starts with $")
        return None

    def _substitute(self, value: Any, loc: Loc, env: _Env) -> tuple[Any, bool]:
        """Replace $task/$param inside a literal list or mapping.  Returns
        (value, known); ``known`` is False when a part has no value yet."""
        if isinstance(value, str) and value.startswith("$"):
            if value.startswith("$$"):
                return value[1:], True
            b = self._ref(value, loc, env)
            if b is None:
                return None, False
            if isinstance(b, Key):
                self.error(loc, f"{value} inside a list or mapping", "a blackboard reference must be the whole value "
                           "of a port; put the list itself on the blackboard")
                return None, False
            if isinstance(b, Unknown):
                return None, False
            return b.value, True
        if isinstance(value, list):
            out, known = [], True
            for i, item in enumerate(value):
                v, k = self._substitute(item, value.iloc(i) if isinstance(value, YList) else loc, env)
                out.append(v)
                known = known and k
            return out, known
        if isinstance(value, dict):
            out_d, known = {}, True
            for key, item in value.items():
                v, k = self._substitute(item, value.vloc(key) if isinstance(value, YMap) else loc, env)
                out_d[key] = v
                known = known and k
            return out_d, known
        return value, True

    def _bind(self, port: Port, value: Any, loc: Loc, env: _Env, owner: str) -> Binding | None:
        label = f"port {port.name!r} of {owner}"
        source = None
        if isinstance(value, str) and value.startswith("$") and not value.startswith("$$"):
            b = self._ref(value, loc, env)
            if b is None:
                return None
            if isinstance(b, Key):
                if port.constant:
                    self.error(loc, f"{label} takes a value fixed when the tree loads, not a blackboard key",
                               "write a literal, $task.NAME or $param.NAME")
                    return None
                (self._reads if port.direction == "in" else self._writes).append((b.key, port.ptype, loc, label))
                return b
            if port.direction == "out":
                self.error(loc, f"output {label} must be bound to a blackboard key, not {value}",
                           f"write `{port.name}: $bb.some_key`")
                return None
            if isinstance(b, Unknown):
                if not port.ptype.accepts(b.ptype):
                    self.error(loc, f"{label} expects {port.ptype.name} but {value} is {b.ptype.name}",
                               f"declare {value} as {port.ptype.name}, or bind another value")
                    return None
                return b
            value, source = b.value, value
        if port.direction == "out":
            self.error(loc, f"output {label} must be bound to a blackboard key",
                       f"write `{port.name}: $bb.some_key`")
            return None
        if port.ptype is EXPR:
            return self._expr(value, loc, env, label, source)
        value, known = self._substitute(value, loc, env)
        if not known:
            return Unknown(port.ptype, source or str(value))
        if value is None and not port.required:
            return Const(port.default, "null")
        try:
            return Const(port.check(value), source if source is not None else _show(value))
        except PortTypeError as exc:
            hint = f"give a {port.ptype.name}" + (f" such as {port.default!r}" if port.default is not None else "")
            if port.choices:
                hint = did_you_mean(str(value), map(str, port.choices), "choices")
            self.error(loc, f"{label}: {exc}", hint + "; or bind it to a blackboard key with $bb.KEY"
                       if not port.constant else hint)
            return None

    def _expr(self, text: Any, loc: Loc, env: _Env, label: str, source: str | None = None) -> Binding | None:
        if not isinstance(text, str):
            self.error(loc, f"{label}: a condition must be text, got {type(text).__name__}",
                       "write the condition as text, e.g. \"attempts < 3\"")
            return None

        def resolve_key(name: str) -> str:
            return env.key(name)

        def resolve_ref(ref: str, pos: int):
            b = self._ref(ref, loc.shifted(pos), env)
            if b is None:
                raise ExprError(f"bad reference {ref}", pos, "see the error above")
            if isinstance(b, Key):
                return ("key", b.key)
            if isinstance(b, Unknown):
                return ("const", None)
            return ("const", b.value)
        try:
            e = parse_expr(text, resolve_key, resolve_ref)
        except ExprError as exc:
            if exc.message.startswith("bad reference"):
                return None
            self.error(loc.shifted(exc.offset), f"{label}: {exc.message} in condition {text!r}", exc.hint)
            return None
        for k in e.keys:
            self._reads.append((k, port_type("any"), loc, label))
        return Const(e, source or text)

    # -- nodes -----------------------------------------------------------------
    def _root_node(self, f: _File, env: _Env) -> NodeSpec | None:
        if f.doc is None or "root" not in f.doc:
            return None
        return self._node(f.doc["root"], f.doc.vloc("root"), env)

    def _node(self, value: Any, loc: Loc, env: _Env) -> NodeSpec | None:
        if isinstance(value, str):
            tname, opts, oloc = value, None, loc
        elif isinstance(value, YMap):
            if len(value) != 1:
                self._bad_node_mapping(value)
                return None
            tname = next(iter(value))
            opts, oloc, loc = value[tname], value.vloc(tname), value.kloc(tname)
        elif isinstance(value, YList):
            self.error(value.loc, "a list is not a node",
                       "put the nodes under a composite, e.g. `reactive_sequence: {children: [...]}`")
            return None
        else:
            self.error(loc, f"expected a node, found {type(value).__name__} {value!r}",
                       "a node is a type name, or a mapping `TYPE: {port: value, ...}`")
            return None
        if not isinstance(tname, str):
            self.error(loc, f"node type must be a name, not {tname!r}", "e.g. `wait: {seconds: 1}`")
            return None
        nt = self.registry.get(tname)
        if nt is None:
            hint = _AMBIGUOUS.get(tname) or did_you_mean(tname, self.registry.names(), "node types")
            self.error(loc, f"unknown node type {tname!r}", hint + "; `rll-bt tree nodes` lists them all")
            return None
        if opts is None:
            opts = YMap(oloc)
        elif isinstance(opts, YList):
            many = [s for s in nt.slots if s.many]
            if not many:
                self.error(oloc, f"{tname} takes a mapping of ports, not a list",
                           f"write `{tname}: {{...}}`" + ("; its child goes under `child:`"
                                                           if any(s.name == "child" for s in nt.slots) else ""))
                return None
            m = YMap(oloc)
            m[many[0].name] = opts
            m.key_locs[many[0].name] = oloc
            m.value_locs[many[0].name] = oloc
            opts = m
        elif not isinstance(opts, YMap):
            self.error(oloc, f"the ports of {tname} must be a mapping, got {type(opts).__name__} {opts!r}",
                       f"write `{tname}: {{port: value}}`" + (f"; {tname} has ports: {', '.join(nt.ports)}"
                                                               if nt.ports else f"; {tname} has no ports: `- {tname}`"))
            return None
        if nt.kind == "subtree":
            return self._subtree(nt, opts, loc, env)
        return self._plain_node(nt, opts, loc, env)

    def _bad_node_mapping(self, value: YMap) -> None:
        keys = list(value)
        if not keys:
            self.error(value.loc, "empty mapping where a node was expected", "write a node such as `success`")
            return
        types = [k for k in keys if isinstance(k, str) and k in self.registry]
        if len(types) == 1:
            nt = self.registry.get(types[0])
            known = set(nt.ports) | {s.name for s in nt.slots} | {"name"}
            strays = [k for k in keys if k != types[0]]
            if all(k in known for k in strays):
                self.error(value.kloc(strays[0]), f"{', '.join(map(repr, strays))} is not indented under "
                           f"{types[0]!r}: a node is a mapping with exactly one key, its type",
                           f"indent {', '.join(map(str, strays))} further than `{types[0]}:` "
                           f"(or write `{types[0]}: {{{strays[0]}: ...}}`)")
                return
        self.error(value.loc, f"a node is a mapping with exactly one key, its type; found {len(keys)} keys "
                   f"({', '.join(map(str, keys[:4]))})",
                   "each node is its own list item (start each with '-'), and its ports are indented under its type")

    def _plain_node(self, nt: NodeType, opts: YMap, loc: Loc, env: _Env) -> NodeSpec | None:
        ok = True
        name = opts.get("name", nt.name)
        if not isinstance(name, str) or not name:
            self.error(opts.vloc("name"), "`name` must be non-empty text", "e.g. name: approach station")
            name, ok = nt.name, False
        slot_names = {s.name for s in nt.slots}
        spec = NodeSpec(nt.name, name, loc, nt.kind, scope=env.scope, nodetype=nt)
        for key in opts:
            if key == "name" or key in slot_names:
                continue
            port = nt.ports.get(key)
            if port is None:
                choices = list(nt.ports) + sorted(slot_names)
                self.error(opts.kloc(key), f"unknown port {key!r} for node type {nt.name!r}",
                           (did_you_mean(str(key), choices, "ports") if choices else f"{nt.name} has no ports")
                           + f"; see `rll-bt tree nodes {nt.name}`")
                ok = False
                continue
            b = self._bind(port, opts[key], opts.vloc(key), env, repr(nt.name))
            if b is None:
                ok = False
            else:
                spec.ports[key] = b
        for pname, port in nt.ports.items():
            if pname not in spec.ports and port.required and pname not in opts:
                example = "$bb.some_key" if port.direction == "out" else _example(port)
                self.error(loc, f"node type {nt.name!r} requires port {pname!r} ({port.ptype.name})",
                           f"add `{pname}: {example}`" + (f" ({port.doc})" if port.doc else ""))
                ok = False
        for slot in nt.slots:
            v = opts.get(slot.name)
            vloc = opts.vloc(slot.name)
            if v is None:
                if slot.required:
                    what = "a list of child nodes" if slot.many else "a child node"
                    self.error(loc, f"{nt.name} needs `{slot.name}:` with {what}",
                               f"add `{slot.name}:` indented under `{nt.name}:`")
                    ok = False
                continue
            if slot.many:
                if not isinstance(v, YList):
                    self.error(vloc, f"`{slot.name}` of {nt.name} must be a list of nodes",
                               f"write each child as a list item: `{slot.name}:\\n  - success`")
                    ok = False
                    continue
                if not v and slot.required:
                    self.error(vloc, f"`{slot.name}` of {nt.name} is empty", "give it at least one node")
                    ok = False
                kids = [self._node(item, v.iloc(i), env) for i, item in enumerate(v)]
                if any(k is None for k in kids):
                    ok = False
                spec.slots[slot.name] = [k for k in kids if k is not None]
            else:
                if slot.expr and isinstance(v, str):
                    cond_t = self.registry.get(v)
                    if cond_t is None or cond_t.kind != "condition":
                        b = self._expr(v, vloc, env, f"`{slot.name}` of {nt.name!r}")
                        if b is None:
                            ok = False
                        else:
                            spec.ports[slot.name] = b
                        continue
                kid = self._node(v, vloc, env)
                if kid is None:
                    ok = False
                else:
                    if slot.expr and kid.kind != "condition":
                        self.error(vloc, f"`{slot.name}` of {nt.name} must be a condition, "
                                   f"but {kid.type!r} is an {kid.kind}",
                                   "use a condition node type or a condition expression such as \"holding == true\"")
                        ok = False
                    spec.slots[slot.name] = [kid]
        if ok and nt.check is not None:
            for loc_, msg, hint in nt.check(spec, opts) or ():
                self.error(loc_, msg, hint)
                ok = False
        infer = getattr(nt.cls, "infer_output_types", None) if nt.cls is not None else None
        if ok and infer is not None:
            for pname, t in (infer(spec) or {}).items():
                b = spec.ports.get(pname)
                if isinstance(b, Key):
                    self._writes[:] = [w for w in self._writes if not (w[0] == b.key and w[2] == opts.vloc(pname))]
                    self._writes.append((b.key, t, opts.vloc(pname), f"port {pname!r} of {nt.name!r}"))
        return spec if ok else None

    # -- subtrees ----------------------------------------------------------------
    def _subtree(self, nt: NodeType, opts: YMap, loc: Loc, env: _Env) -> NodeSpec | None:
        for key in opts:
            if key not in nt.ports and key != "name":
                self.error(opts.kloc(key), f"unknown field {key!r} of subtree",
                           did_you_mean(str(key), list(nt.ports) + ["name"], "fields"))
                return None
        fname = opts.get("file")
        if not isinstance(fname, str) or not fname:
            self.error(opts.vloc("file") if "file" in opts else loc, "subtree needs `file:` with a path",
                       "e.g. subtree: {file: common/relocalise.yaml}")
            return None
        floc = opts.vloc("file")
        here = env.file.path.parent
        candidates = [here / fname] + [sp / fname for sp in self.search_path]
        path = next((c.resolve() for c in candidates if c.is_file()), None)
        if path is None:
            near = sorted(str(p.relative_to(here)) for p in here.rglob("*.yaml")) if here.is_dir() else []
            looked = ', '.join(_display(c.parent) for c in candidates)
            self.error(floc, f"subtree file {fname!r} not found (looked in {looked})",
                       did_you_mean(fname, near, "tree files nearby") if near else "check the path; it is relative to "
                       "the including file")
            return None
        if path in env.stack:
            chain = " -> ".join(_display(p) for p in env.stack[env.stack.index(path):]) + " -> " + _display(path)
            self.error(floc, f"subtree cycle: {chain}",
                       "a tree may not include itself, directly or through its subtrees")
            return None
        child = self._read(path)
        if child is None:
            if not any(d.loc.file == _display(path) for d in self.diags):
                self.error(floc, f"subtree file {fname!r} cannot be loaded", "see the errors in that file")
            return None
        # instance name = blackboard scope
        explicit = "name" in opts
        name = opts.get("name", child.name)
        if not isinstance(name, str) or not _SEGMENT.match(name):
            self.error(opts.vloc("name") if explicit else floc, f"subtree instance name {name!r} is not a valid "
                       "scope name", "name it with letters, digits and '_' (it becomes its blackboard scope)")
            return None
        used = self._scope_names.setdefault(env.scope, set())
        if name in used:
            if explicit:
                self.error(opts.vloc("name"), f"two subtree instances named {name!r} share the blackboard "
                           f"scope {env.scope}{name}/", "give each instance its own `name:`")
                return None
            i = 2
            while f"{name}_{i}" in used:
                i += 1
            name = f"{name}_{i}"
        used.add(name)
        scope = env.scope + name + "/"
        ok = True
        # parameters
        params: dict[str, Binding] = {}
        given = opts.get("params") or {}
        if not isinstance(given, YMap) and given != {}:
            self.error(opts.vloc("params"), "`params` must map parameter names to values",
                       "e.g. params: {side: input}")
            return None
        for k in given:
            decl = child.params.get(k)
            if decl is None:
                self.error(given.kloc(k), f"{_display(path)} has no parameter {k!r}",
                           did_you_mean(str(k), child.params, "parameters") if child.params
                           else "that tree declares no `params:`")
                ok = False
                continue
            port = Input(decl.ptype, decl.doc, default=decl.default if not decl.required else None,
                         choices=decl.choices, name=k)
            b = self._bind(port, given[k], given.vloc(k), env, f"subtree {name!r}")
            if b is None:
                ok = False
            else:
                params[k] = b
        for k, decl in child.params.items():
            if k not in params and k not in given:
                if decl.required:
                    self.error(loc, f"subtree {name!r} ({_display(path)}) requires parameter {k!r}",
                               f"add `params: {{{k}: ...}}`" + (f" ({decl.doc})" if decl.doc else ""))
                    ok = False
                else:
                    params[k] = Const(decl.default, f"$param.{k}")
        # remapping
        remap: dict[str, str] = {}
        rm = opts.get("remap") or {}
        if not isinstance(rm, YMap) and rm != {}:
            self.error(opts.vloc("remap"), "`remap` must map keys of the subtree to $bb keys here",
                       "e.g. remap: {target: $bb.goal_pose}")
            return None
        for k in rm:
            v = rm[k]
            if not isinstance(k, str) or not valid_key(k) or k.startswith("/"):
                self.error(rm.kloc(k), f"{k!r} is not a key of the subtree's scope",
                           "remap relative keys (no leading '/'): they are the subtree's own $bb names")
                ok = False
                continue
            if not isinstance(v, str) or not v.startswith("$bb."):
                self.error(rm.vloc(k), f"remap of {k!r} must be a blackboard key here ($bb.KEY), not {v!r}",
                           "constants go in `params:`")
                ok = False
                continue
            b = self._ref(v, rm.vloc(k), env)
            if b is None:
                ok = False
                continue
            remap[k] = b.key
        autoremap = opts.get("autoremap", False)
        if not isinstance(autoremap, bool):
            self.error(opts.vloc("autoremap"), "`autoremap` must be true or false", "")
            return None
        if not ok:
            return None
        cenv = _Env(child, scope, params, remap, autoremap, env, env.stack + (path,))
        self._init_blackboard(child, cenv)
        root = self._root_node(child, cenv)
        if root is None:
            return None
        return NodeSpec("subtree", name, loc, "subtree", {"file": Const(fname, fname)}, {"root": [root]},
                        scope, child.display, nt)

    # -- blackboard ----------------------------------------------------------------
    def _init_blackboard(self, f: _File, env: _Env) -> None:
        for name, decl in f.blackboard.items():
            key = env.key(name)
            self._writes.append((key, decl.ptype, decl.loc, f"blackboard declaration {name!r}"))
            if decl.default is not None:
                self._bb_init[key] = decl.default

    def _check_key_types(self) -> None:
        writers: dict[str, tuple[PortType, Loc, str]] = {}
        for key, t, loc, what in self._writes:
            if t.name == "any":
                continue
            first = writers.get(key)
            if first is None:
                writers[key] = (t, loc, what)
            elif not (first[0].accepts(t) or t.accepts(first[0])):
                self.error(loc, f"{what} writes {t.name} to {key}, which {first[2]} at {first[1]} writes as "
                           f"{first[0].name}", "use one type per blackboard key, or another key")
        for key, t, loc, what in self._reads:
            w = writers.get(key)
            if w is not None and not t.accepts(w[0]):
                self.error(loc, f"{what} expects {t.name} but blackboard key {key} holds {w[0].name} "
                           f"(written by {w[2]} at {w[1]})", "bind a key of the right type, or convert the value")


def _check_decl(decl: Decl, value: Any) -> Any:
    if value is None:
        return None
    if isinstance(value, str) and decl.ptype.name not in ("str", "expr", "any") and getattr(value, "from_cli", False):
        value = decl.ptype.from_text(value)
    v = decl.ptype.coerce(value)
    if decl.choices and v not in decl.choices:
        raise PortTypeError(f"expected one of {', '.join(map(str, decl.choices))}; got {v!r}")
    return v


def _show(value: Any) -> str:
    if isinstance(value, str):
        return value
    if isinstance(value, bool):
        return "true" if value else "false"
    if value is None:
        return "null"
    return repr(value)


def _example(port: Port) -> str:
    if port.choices:
        return str(port.choices[0])
    return {"bool": "true", "int": "1", "float": "1.0", "str": "\"...\"", "list": "[]", "dict": "{}",
            "pose": "{x: 0.0, y: 0.0, theta: 0.0}", "expr": "\"key == true\""}.get(port.ptype.name, "...")


class CliText(str):
    """A value typed on the command line: converted to the declared type."""
    from_cli = True


def parse_tree(path: str | Path, *, task: Mapping[str, Any] | None = None, params: Mapping[str, Any] | None = None,
               registry: NodeRegistry | None = None, search_path: Iterable[str | Path] = (),
               strict: bool = False, text: str | None = None) -> TreeSpec:
    """Parse and check a tree file (no behaviours are made).

    ``task=None`` checks without a task; raises :class:`TreeLoadError`
    listing every problem with ``file:line:column`` and a hint.  ``text``
    parses a string instead of reading ``path`` (``path`` names it)."""
    return Loader(registry, task, params, search_path, strict).load(path, text)
