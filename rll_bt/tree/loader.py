"""Tree files to :class:`~rll_bt.tree.spec.TreeSpec`: parse, resolve, check.

Every problem is collected as a :class:`~rll_bt.tree.errors.Diagnostic`
with ``file:line:column`` and a hint; if any was found,
:class:`~rll_bt.tree.errors.TreeLoadError` lists them all.  Nothing in a
tree file is ever executed: node types must be registered, conditions are
parsed by :mod:`rll_bt.tree.expr`, and YAML is read with ``safe_load``
semantics (:mod:`rll_bt.tree.source`).  The header of a file is read by
:mod:`.files`, values are bound to ports by :mod:`.binding`, subtree files
are included by :mod:`.include`, and the blackboard keys are checked by
:mod:`.keys`.
"""
from __future__ import annotations

from collections.abc import Iterable, Mapping
from pathlib import Path
from typing import Any

from .binding import Binder
from .errors import Diagnostic, Loc, TreeLoadError, did_you_mean
from .files import HEADER_KEYS, CliText, Instance, TreeFile, check_value, display, read_decls, valid_key
from .include import include
from .keys import KeyBook
from .ports import Binding, Const, Key, Port, Unknown
from .porttypes import PortTypeError
from .registry import NodeRegistry, NodeType, default_registry
from .source import SourceError, YList, YMap, parse_yaml
from .spec import NodeSpec, TreeSpec

__all__ = ["CliText", "Loader", "parse_tree", "valid_key"]

_AMBIGUOUS = {
    "sequence": "say whether it remembers: `sequence_with_memory` (resume at the running child) "
                "or `reactive_sequence` (re-check from the first child every tick)",
    "selector": "say whether it remembers: `selector_with_memory` (resume at the running child) "
                "or `reactive_selector` (re-try higher priorities every tick)",
    "fallback": "fallbacks are selectors: use `selector_with_memory` or `reactive_selector`",
}


class Loader:
    """Resolves one root tree file.  ``task=None`` checks without a task
    (``$task.x`` stays symbolic); ``strict`` demands every required task field
    and parameter."""

    def __init__(self, registry: NodeRegistry | None = None, task: Mapping[str, Any] | None = None,
                 params: Mapping[str, Any] | None = None, search_path: Iterable[str | Path] = (),
                 strict: bool = False):
        self.registry = registry or default_registry()
        self.root_params = dict(params or {})
        self.search_path = [Path(p) for p in search_path]
        self.strict = strict
        self.diags: list[Diagnostic] = []
        self.keys = KeyBook()
        self.binder = Binder(self.error, self.keys, task, strict)
        self.scope_names: dict[str, set[str]] = {}
        self._files: dict[Path, TreeFile | None] = {}
        self._bb_init: dict[str, Any] = {}
        self._files_used: list[str] = []

    # -- reporting -------------------------------------------------------------
    def error(self, loc: Loc, message: str, hint: str = "") -> None:
        self.diags.append(Diagnostic(loc, message, hint))

    # -- entry -----------------------------------------------------------------
    def load(self, path: str | Path, text: str | None = None) -> TreeSpec:
        p = Path(path)
        f = self.read(p.resolve() if text is None else p, text, shown=str(path))
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
                params[k] = Const(check_value(decl, v), f"$param.{k}")
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
        env = Instance(f, "/", params, {}, False, None, (f.path,))
        root = self.instantiate(f, env)
        self.keys.check(self.error)
        if self.diags or root is None:
            raise TreeLoadError(self.diags or [Diagnostic(loc0, "the tree has no root", "add `root:`")])
        return TreeSpec(f.display, f.name, (f.doc or {}).get("doc", "") or "", root, f.task, f.params,
                        dict(self._bb_init), self.keys.types(), list(dict.fromkeys(self._files_used)),
                        f.outputs, {name: env.key(name) for name in f.outputs})

    # -- files -----------------------------------------------------------------
    def read(self, path: Path, text: str | None = None, shown: str | None = None) -> TreeFile | None:
        """The header of the file at ``path`` (read once; None after reporting)."""
        if path in self._files:
            return self._files[path]
        disp = shown or display(path)
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
                       "name, doc, task, params, outputs, blackboard)", "start the file with `root:`")
            return None
        f = TreeFile(path, disp, doc, name=str(doc.get("name") or path.stem))
        for k in doc:
            if k not in HEADER_KEYS:
                self.error(doc.kloc(k), f"unknown top-level key {k!r}",
                           did_you_mean(str(k), HEADER_KEYS, "top-level keys"))
        for k in ("name", "doc"):
            if k in doc and not isinstance(doc[k], str):
                self.error(doc.vloc(k), f"`{k}` must be text", f"write {k}: \"...\"")
        if "root" not in doc:
            self.error(loc0, "the tree has no `root:`", "add `root:` with the top node of the tree")
        f.task = read_decls(doc, "task", self.error)
        f.params = read_decls(doc, "params", self.error)
        f.outputs = read_decls(doc, "outputs", self.error)
        f.blackboard = read_decls(doc, "blackboard", self.error, keys=True)
        self._files[path] = f
        self._files_used.append(disp)
        return f

    def instantiate(self, f: TreeFile, env: Instance) -> NodeSpec | None:
        """The root node of ``f`` in the instance ``env``, with its blackboard
        declarations; each declared output must be written by a node of it."""
        for name, decl in f.blackboard.items():
            key = env.key(name)
            self.keys.write(key, decl.ptype, decl.loc, f"blackboard declaration {name!r}")
            if decl.default is not None:
                self._bb_init[key] = decl.default
        for name, decl in f.outputs.items():
            self.keys.declare_output(env.key(name), decl.ptype, decl.loc, f"output {name!r} of {f.display}")
        if f.doc is None or "root" not in f.doc:
            return None
        mark = self.keys.mark()
        root = self._node(f.doc["root"], f.doc.vloc("root"), env)
        if root is not None:
            for name, decl in f.outputs.items():
                if not self.keys.written_since(mark, env.key(name)):
                    self.error(decl.loc, f"output {name!r} is declared but nothing in {f.display} writes it",
                               f"bind an output port to $bb.{name} (or write it with set_blackboard), "
                               "or remove the declaration")
        return root

    # -- nodes -----------------------------------------------------------------
    def _node(self, value: Any, loc: Loc, env: Instance) -> NodeSpec | None:
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
            return include(self, nt, opts, loc, env)
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

    def _plain_node(self, nt: NodeType, opts: YMap, loc: Loc, env: Instance) -> NodeSpec | None:
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
            b = self.binder.bind(port, opts[key], opts.vloc(key), env, repr(nt.name))
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
                        b = self.binder.expr(v, vloc, env, f"`{slot.name}` of {nt.name!r}")
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
                    self.keys.retype(b.key, t, opts.vloc(pname), f"port {pname!r} of {nt.name!r}")
        return spec if ok else None


def _example(port: Port) -> str:
    if port.choices:
        return str(port.choices[0])
    return {"bool": "true", "int": "1", "float": "1.0", "str": "\"...\"", "list": "[]", "dict": "{}",
            "pose": "{x: 0.0, y: 0.0, theta: 0.0}", "expr": "\"key == true\""}.get(port.ptype.name, "...")


def parse_tree(path: str | Path, *, task: Mapping[str, Any] | None = None, params: Mapping[str, Any] | None = None,
               registry: NodeRegistry | None = None, search_path: Iterable[str | Path] = (),
               strict: bool = False, text: str | None = None) -> TreeSpec:
    """Parse and check a tree file (no behaviours are made).

    ``task=None`` checks without a task; raises :class:`TreeLoadError`
    listing every problem with ``file:line:column`` and a hint.  ``text``
    parses a string instead of reading ``path`` (``path`` names it)."""
    return Loader(registry, task, params, search_path, strict).load(path, text)
