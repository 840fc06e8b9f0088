"""How the loader includes a file for a ``subtree`` node.

The file is found (relative to the including file, then on the search
path), checked for cycles, read once, and instantiated in a blackboard
scope of its own (``/<instance name>/`` under the caller's scope).  Its
parameters come from ``params:`` (a value each) and ``pass:`` (the
caller's parameters or task fields of the same name: a list of names, or
``all``).  Its keys map to the caller's through ``remap:`` and
``autoremap:``; the keys it declares under ``outputs:`` are the caller's
keys of the same name unless ``remap:`` sends them elsewhere.
"""
from __future__ import annotations

from pathlib import Path
from typing import Protocol

from .binding import Binder
from .errors import Diagnostic, Loc, did_you_mean
from .files import SEGMENT, Instance, TreeFile, display, valid_key
from .ports import Binding, Const, Input
from .registry import NodeType
from .source import YList, YMap
from .spec import NodeSpec


class Loader(Protocol):
    """What including a file needs of the loader (:class:`rll_bt.tree.loader.Loader`)."""
    search_path: list[Path]
    scope_names: dict[str, set[str]]
    diags: list[Diagnostic]
    binder: Binder

    def error(self, loc: Loc, message: str, hint: str = "") -> None: ...
    def read(self, path: Path) -> TreeFile | None: ...
    def instantiate(self, f: TreeFile, env: Instance) -> NodeSpec | None: ...


def include(ld: Loader, nt: NodeType, opts: YMap, loc: Loc, env: Instance) -> NodeSpec | None:
    """The ``subtree`` node written at ``loc`` in ``env`` (None after reporting)."""
    fields = [*nt.ports, "name"]
    for key in opts:
        if key not in fields:
            ld.error(opts.kloc(key), f"unknown field {key!r} of subtree", did_you_mean(str(key), fields, "fields"))
            return None
    fname = opts.get("file")
    if not isinstance(fname, str) or not fname:
        ld.error(opts.vloc("file") if "file" in opts else loc, "subtree needs `file:` with a path",
                 "e.g. subtree: {file: common/relocalise.yaml}")
        return None
    floc = opts.vloc("file")
    here = env.file.path.parent
    candidates = [here / fname] + [sp / fname for sp in ld.search_path]
    path = next((c.resolve() for c in candidates if c.is_file()), None)
    if path is None:
        near = sorted(str(p.relative_to(here)) for p in here.rglob("*.yaml")) if here.is_dir() else []
        looked = ', '.join(display(c.parent) for c in candidates)
        ld.error(floc, f"subtree file {fname!r} not found (looked in {looked})",
                 did_you_mean(fname, near, "tree files nearby") if near else "check the path; it is relative to "
                 "the including file")
        return None
    if path in env.stack:
        chain = " -> ".join(display(p) for p in env.stack[env.stack.index(path):]) + " -> " + display(path)
        ld.error(floc, f"subtree cycle: {chain}", "a tree may not include itself, directly or through its subtrees")
        return None
    child = ld.read(path)
    if child is None:
        if not any(d.loc.file == display(path) for d in ld.diags):
            ld.error(floc, f"subtree file {fname!r} cannot be loaded", "see the errors in that file")
        return None
    name = _instance_name(ld, opts, floc, env, child)
    if name is None:
        return None
    params = _params(ld, opts, loc, env, child, name)
    remap = _remap(ld, opts, env, child)
    autoremap = opts.get("autoremap", False)
    if not isinstance(autoremap, bool):
        ld.error(opts.vloc("autoremap"), "`autoremap` must be true or false", "")
        return None
    if params is None or remap is None:
        return None
    for out in child.outputs:               # outputs go to the caller's key of the same name
        remap.setdefault(out, env.key(out))
    scope = env.scope + name + "/"
    cenv = Instance(child, scope, params, remap, autoremap, env, env.stack + (path,))
    root = ld.instantiate(child, cenv)
    if root is None:
        return None
    return NodeSpec("subtree", name, loc, "subtree", {"file": Const(fname, fname)}, {"root": [root]},
                    scope, child.display, nt)


def _instance_name(ld: Loader, opts: YMap, floc: Loc, env: Instance, child: TreeFile) -> str | None:
    """The instance name (its blackboard scope): ``name:``, else the file's
    name, numbered when the scope already has one of that name."""
    explicit = "name" in opts
    name = opts.get("name", child.name)
    if not isinstance(name, str) or not SEGMENT.match(name):
        ld.error(opts.vloc("name") if explicit else floc, f"subtree instance name {name!r} is not a valid "
                 "scope name", "name it with letters, digits and '_' (it becomes its blackboard scope)")
        return None
    used = ld.scope_names.setdefault(env.scope, set())
    if name in used:
        if explicit:
            ld.error(opts.vloc("name"), f"two subtree instances named {name!r} share the blackboard "
                     f"scope {env.scope}{name}/", "give each instance its own `name:`")
            return None
        i = 2
        while f"{name}_{i}" in used:
            i += 1
        name = f"{name}_{i}"
    used.add(name)
    return name


def passed_names(value, child_params, caller: TreeFile) -> list[str]:
    """The names ``pass:`` gives (``all``: every parameter of the child that
    the caller has as a parameter or task field), in the child's order."""
    if value == "all":
        return [k for k in child_params if k in caller.params or k in caller.task]
    return [k for k in value if isinstance(k, str)]


def _params(ld: Loader, opts: YMap, loc: Loc, env: Instance, child: TreeFile, name: str) -> dict[str, Binding] | None:
    ok = True
    params: dict[str, Binding] = {}
    given = opts.get("params") or {}
    if not isinstance(given, YMap) and given != {}:
        ld.error(opts.vloc("params"), "`params` must map parameter names to values", "e.g. params: {side: INPUT}")
        return None
    sources: dict[str, tuple[object, Loc]] = {k: (given[k], given.vloc(k)) for k in given}
    passing = opts.get("pass")
    if passing is not None:
        if passing != "all" and not (isinstance(passing, YList) and all(isinstance(k, str) for k in passing)):
            ld.error(opts.vloc("pass"), "`pass` takes a list of parameter names or `all`",
                     "e.g. pass: [machine, side] (the caller's $param or $task of the same name)")
            return None
        if passing == "all":        # what `params:` gives explicitly stays
            items = [(k, opts.vloc("pass")) for k in passed_names("all", child.params, env.file) if k not in sources]
        else:
            items = [(k, passing.iloc(i)) for i, k in enumerate(passing)]
        for k, kloc in items:
            if k in sources:
                ld.error(kloc, f"parameter {k!r} is both passed and given in `params:`", "keep one of the two")
                ok = False
            elif k in env.file.params:
                sources[k] = (f"$param.{k}", kloc)
            elif k in env.file.task:
                sources[k] = (f"$task.{k}", kloc)
            else:
                ld.error(kloc, f"cannot pass {k!r}: {env.file.display} has no parameter or task field {k!r}",
                         f"declare it under `params:` or `task:`, or give it in `params: {{{k}: ...}}`")
                ok = False
    for k, (value, vloc) in sources.items():
        decl = child.params.get(k)
        if decl is None:
            ld.error(given.kloc(k) if k in given else vloc, f"{display(child.path)} has no parameter {k!r}",
                     did_you_mean(str(k), child.params, "parameters") if child.params
                     else "that tree declares no `params:`")
            ok = False
            continue
        port = Input(decl.ptype, decl.doc, default=decl.default if not decl.required else None,
                     choices=decl.choices, name=k)
        b = ld.binder.bind(port, value, vloc, env, f"subtree {name!r}")
        if b is None:
            ok = False
        else:
            params[k] = b
    for k, decl in child.params.items():
        if k not in params and k not in sources:
            if decl.required:
                ld.error(loc, f"subtree {name!r} ({display(child.path)}) requires parameter {k!r}",
                         f"add `params: {{{k}: ...}}` or `pass: [{k}]`" + (f" ({decl.doc})" if decl.doc else ""))
                ok = False
            else:
                params[k] = Const(decl.default, f"$param.{k}")
    return params if ok else None


def _remap(ld: Loader, opts: YMap, env: Instance, child: TreeFile) -> dict[str, str] | None:
    remap: dict[str, str] = {}
    rm = opts.get("remap") or {}
    if not isinstance(rm, YMap) and rm != {}:
        ld.error(opts.vloc("remap"), "`remap` must map keys of the subtree to $bb keys here",
                 "e.g. remap: {target: $bb.goal_pose}")
        return None
    ok = True
    for k in rm:
        v = rm[k]
        if not isinstance(k, str) or not valid_key(k) or k.startswith("/"):
            ld.error(rm.kloc(k), f"{k!r} is not a key of the subtree's scope",
                     "remap relative keys (no leading '/'): they are the subtree's own $bb names")
            ok = False
            continue
        if not isinstance(v, str) or not v.startswith("$bb."):
            ld.error(rm.vloc(k), f"remap of {k!r} must be a blackboard key here ($bb.KEY), not {v!r}",
                     "constants go in `params:`")
            ok = False
            continue
        b = ld.binder.ref(v, rm.vloc(k), env)
        if b is None:
            ok = False
            continue
        remap[k] = b.key
    return remap if ok else None
