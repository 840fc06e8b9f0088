"""Turn a checked :class:`TreeSpec` into py_trees behaviours."""
from __future__ import annotations

from collections.abc import Iterable, Mapping
from pathlib import Path
from typing import Any

from .context import RunContext
from .errors import Diagnostic, TreeLoadError
from .loader import parse_tree
from .ports import BoundPorts, Unknown
from .registry import NodeRegistry
from .runtime import LoadedTree, NodeInfo
from .spec import NodeSpec, TreeSpec


def build_tree(spec: TreeSpec, ctx: RunContext | None = None) -> LoadedTree:
    """Make the behaviours of ``spec`` for ``ctx`` (a fresh context by
    default).  Node types' required services and backend capabilities are
    checked here; problems raise :class:`TreeLoadError` with the node's place."""
    ctx = ctx or RunContext()
    diags: list[Diagnostic] = []
    nodes: list[NodeInfo] = []
    for key, value in spec.blackboard_init.items():
        if key not in ctx.blackboard:
            ctx.blackboard.set(key, value)
    caps = None
    if ctx.backend is not None:
        try:
            caps = ctx.backend.capabilities
        except Exception:   # a backend that cannot tell: do not guess
            caps = None

    def make(ns: NodeSpec, parent: int | None, depth: int):
        nt = ns.nodetype
        my_id = len(nodes)
        nodes.append(None)  # reserve the pre-order id
        kids: dict[str, list] = {}
        for slot, specs in ns.slots.items():
            kids[slot] = [make(c, my_id, depth + 1) for c in specs]
        for _pname, b in ns.ports.items():
            if isinstance(b, Unknown):
                diags.append(Diagnostic(ns.loc, f"{b.source} has no value", "load the tree with a task that gives it"))
                return None
        if any(k is None for ks in kids.values() for k in ks):
            return None
        try:
            if nt.cls is not None:
                cls = nt.cls
                missing = [s for s in cls.requires_services if not ctx.has_service(s)]
                if missing:
                    diags.append(Diagnostic(ns.loc, f"{ns.type!r} needs service(s) {', '.join(missing)}, "
                                            "which the run context does not provide",
                                            "the agent provides services; a skills package can register "
                                            "factories with rll_bt.tree.register_service"))
                    return None
                need = cls.requires_capabilities
                if caps is not None and need and (need & caps) != need:
                    diags.append(Diagnostic(ns.loc, f"{ns.type!r} needs backend capabilities {need!r}, "
                                            f"which the backend lacks (it has {caps!r})",
                                            "run this tree on a backend with those capabilities"))
                    return None
                b = cls(ns.name, BoundPorts(ns.ports, ctx.blackboard), ctx)
            else:
                b = nt.build(ns, kids, ctx)
        except Exception as exc:   # report a node that cannot be made, at its place
            diags.append(Diagnostic(ns.loc, f"cannot create {ns.type!r}: {exc}",
                                    f"check the values given to {ns.type}"))
            return None
        b.spec = ns
        nodes[my_id] = NodeInfo(my_id, parent, depth, b, ns)
        return b

    root = make(spec.root, None, 0)
    if diags or root is None:
        raise TreeLoadError(diags)
    return LoadedTree(root, ctx, spec, nodes)


def load_tree(path: str | Path, *, task: Mapping[str, Any] | None = None, params: Mapping[str, Any] | None = None,
              ctx: RunContext | None = None, registry: NodeRegistry | None = None,
              search_path: Iterable[str | Path] = (), text: str | None = None) -> LoadedTree:
    """Load a tree file for a task and build it, ready to tick.

    ``task`` fills ``$task.NAME`` (and becomes ``ctx.task``), ``params`` the
    root file's ``params``.  Raises :class:`TreeLoadError` listing every
    problem with ``file:line:column`` and a hint."""
    task = dict(task or {})
    spec = parse_tree(path, task=task, params=params, registry=registry, search_path=search_path,
                      strict=True, text=text)
    if ctx is None:
        ctx = RunContext(task=task)
    elif dict(ctx.task) != task and task:
        ctx = RunContext(ctx.backend, ctx.clock, task, ctx.logger, ctx.services, ctx.blackboard)
    return build_tree(spec, ctx)
