"""YAML tree files to one BehaviorTree.CPP v4 XML document.

Every file a root file includes (``subtree``) becomes a ``<BehaviorTree>``
of its own, referred to by ``<SubTree ID=...>`` with the subtree's
parameters and remapped keys as port attributes and ``_autoremap``; the
parameters of every tree are declared as the input ports of its ``<SubTree>``
model (its declared outputs as output ports, set on every ``<SubTree>`` to the
caller's entry of the same name unless remapped) and every rll-bt node type the trees use as an ``Action``,
``Condition``, ``Decorator`` or ``Control`` model in ``<TreeNodesModel>``,
so Groot2 shows and edits them.  What BT.CPP has no place for (the file a
tree came from, its name, documentation, task fields and blackboard
declarations) rides in attributes starting with ``_`` on
``<BehaviorTree>`` (BT.CPP itself writes ``_fullpath`` there), so
``rll-bt tree import`` gives back the same trees.
"""
from __future__ import annotations

import json
import posixpath
import xml.etree.ElementTree as ET
from collections.abc import Iterable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from ..errors import Diagnostic, Loc, TreeLoadError
from ..loader import parse_tree
from ..registry import NodeRegistry, NodeType, default_registry
from ..source import SourceError, YList, YMap, parse_yaml
from .mapping import (
    BUILTINS,
    CONVERTED,
    FORMAT,
    PASS_ATTR,
    SAME,
    ValueError_,
    camel,
    model_kind,
    ref_to_text,
    snake,
    value_to_text,
)

_SAME_TO = SAME
_CONVERT_TO = {v[0]: (k, v[1]) for k, v in CONVERTED.items()}


@dataclass
class _Tree:
    path: Path
    rel: str                    # file path relative to the first root's folder
    doc: YMap
    name: str
    id: str = ""
    params: dict[str, dict] = field(default_factory=dict)
    outputs: dict[str, dict] = field(default_factory=dict)


class ExportError(TreeLoadError):
    """A tree that loads but cannot be written as BT.CPP XML."""


class Writer:
    def __init__(self, registry: NodeRegistry | None = None, search_path: Iterable[str | Path] = ()):
        self.registry = registry or default_registry()
        self.search_path = [Path(p) for p in search_path]
        self.trees: dict[Path, _Tree] = {}
        self.order: list[Path] = []
        self.used: dict[str, NodeType] = {}
        self.diags: list[Diagnostic] = []
        self.base: Path | None = None

    # -- files -----------------------------------------------------------------------
    def add(self, path: str | Path) -> _Tree:
        p = Path(path).resolve()
        if self.base is None:
            self.base = p.parent
        if p in self.trees:
            return self.trees[p]
        text = p.read_text(encoding="utf-8")
        try:
            doc = parse_yaml(text, str(path))
        except SourceError as exc:
            raise TreeLoadError([exc.diagnostic]) from None
        rel = posixpath.normpath(Path(p).relative_to(self.base).as_posix()) \
            if p.is_relative_to(self.base) else p.name
        t = _Tree(p, rel, doc, str(doc.get("name") or p.stem))
        self.trees[p] = t
        self.order.append(p)
        for name, decl in (doc.get("params") or {}).items():
            self._param_decl(t, name, decl)
        for name, decl in (doc.get("outputs") or {}).items():
            t.outputs[name] = {"type": decl} if isinstance(decl, str) else dict(decl or {})
        return t

    def _param_decl(self, t: _Tree, name: str, decl: Any) -> None:
        d = {"type": decl} if isinstance(decl, str) else dict(decl or {})
        t.params[name] = d

    def _resolve(self, including: Path, fname: str) -> Path:
        for c in [including.parent / fname] + [sp / fname for sp in self.search_path]:
            if c.is_file():
                return c.resolve()
        raise FileNotFoundError(fname)

    def _assign_ids(self) -> None:
        taken = set(BUILTINS) | {"SubTree"}
        for p in self.order:
            t = self.trees[p]
            base = camel(t.name)
            if base in taken:
                base += "Tree"
            tid, i = base, 2
            while tid in taken:
                tid, i = f"{base}{i}", i + 1
            t.id = tid
            taken.add(tid)

    # -- document --------------------------------------------------------------------
    def document(self, roots: list[str | Path]) -> ET.Element:
        for r in roots:
            parse_tree(r, registry=self.registry, search_path=self.search_path)   # valid first
            self.add(r)
        # every included file, breadth first
        i = 0
        while i < len(self.order):
            t = self.trees[self.order[i]]
            self._collect(t, t.doc.get("root"))
            i += 1
        self._assign_ids()
        root = ET.Element("root", {"BTCPP_format": FORMAT,
                                   "main_tree_to_execute": self.trees[Path(roots[0]).resolve()].id})
        for p in self.order:
            root.append(self._tree(self.trees[p]))
        if self.diags:
            raise ExportError(self.diags)
        root.append(self._model())
        return root

    def _collect(self, t: _Tree, value: Any) -> None:
        tname, opts = _split(value, self.registry)
        if tname is None:
            return
        nt = self.registry.get(tname)
        if nt is None:
            return
        if nt.kind == "subtree":
            path = self._resolve(t.path, opts["file"])
            self.add(path)
            return
        for slot in nt.slots:
            v = opts.get(slot.name)
            if v is None:
                continue
            for item in (v if isinstance(v, list) else [v]):
                self._collect(t, item)

    def _tree(self, t: _Tree) -> ET.Element:
        el = ET.Element("BehaviorTree", {"ID": t.id, "_file": t.rel})
        if snake(t.id) != t.name:
            el.set("_name", t.name)
        doc = t.doc.get("doc")
        if doc:
            el.set("_description", str(doc).strip())
        for section in ("task", "blackboard"):
            block = t.doc.get(section)
            if block:
                el.set("_" + section, json.dumps(_plain(block), separators=(",", ":")))
        el.append(self._node(t, t.doc["root"], t.doc.vloc("root")))
        return el

    # -- nodes -----------------------------------------------------------------------
    def _err(self, loc: Loc, message: str, hint: str = "") -> None:
        self.diags.append(Diagnostic(loc, message, hint))

    def _text(self, value: Any, ptype: str, loc: Loc, what: str) -> str:
        try:
            return value_to_text(value, ptype)
        except ValueError_ as exc:
            self._err(loc, f"{what}: {exc}", "BT.CPP cannot tell such a value from a reference")
            return ""

    def _node(self, t: _Tree, value: Any, loc: Loc) -> ET.Element:
        tname, opts = _split(value, self.registry)
        nt = self.registry.get(tname)
        oloc = value.kloc(tname) if isinstance(value, YMap) else loc
        if nt.kind == "subtree":
            return self._subtree(t, opts, oloc)
        ports = {k: v for k, v in opts.items() if k in nt.ports}
        tag = _SAME_TO.get(tname) or self._converted(nt, ports, opts) or tname
        el = ET.Element(tag)
        if "name" in opts:
            el.set("name", str(opts["name"]))
        if tag in CONVERTED:
            for bport, (port, scale) in CONVERTED[tag][1].items():
                v = ports[port]
                el.set(bport, str(round(v * scale)) if scale else self._text(v, "int", _vloc(opts, port), port))
        else:
            if tag == tname:
                self.used[nt.name] = nt
            for k, v in ports.items():
                el.set(k, self._text(v, nt.ports[k].ptype.name, _vloc(opts, k), f"port {k!r} of {tname!r}"))
        for slot in nt.slots:
            v = opts.get(slot.name)
            if v is None:
                continue
            if slot.expr and isinstance(v, str) and not self._is_condition(v):
                el.set(slot.name, self._text(v, "expr", _vloc(opts, slot.name), f"{slot.name!r} of {tname!r}"))
                continue
            items = list(v) if slot.many else [v]
            for i, item in enumerate(items):
                iloc = v.iloc(i) if isinstance(v, YList) else _vloc(opts, slot.name)
                el.append(self._node(t, item, iloc))
        return el

    def _is_condition(self, name: str) -> bool:
        nt = self.registry.get(name)
        return nt is not None and nt.kind == "condition"

    @staticmethod
    def _converted(nt: NodeType, ports: dict, opts: dict) -> str | None:
        """The BT.CPP built-in for retry/timeout/wait/repeat when the ports fit it exactly."""
        conv = _CONVERT_TO.get(nt.name)
        if conv is None:
            return None
        tag, table = conv
        want = {port for port, _f in table.values()}
        if set(ports) != want or any(s.name in opts for s in nt.slots if not s.required):
            return None
        for port, scale in table.values():
            v = ports[port]
            if not scale and isinstance(v, str) and v.startswith("$") and not v.startswith("$$"):
                continue                        # a count from a reference: the same in both
            if isinstance(v, bool) or not isinstance(v, (int, float)):
                return None
            if scale and (v < 0 or round(v * scale) / scale != v):
                return None
        return tag

    def _subtree(self, t: _Tree, opts: YMap, loc: Loc) -> ET.Element:
        child = self.trees[self._resolve(t.path, opts["file"])]
        el = ET.Element("SubTree", {"ID": child.id})
        if "name" in opts:
            el.set("name", str(opts["name"]))
        params = opts.get("params") or {}
        for k, v in params.items():
            ptype = str(child.params.get(k, {}).get("type", "any"))
            el.set(k, self._text(v, ptype, _vloc(params, k), f"parameter {k!r} of subtree {child.name!r}"))
        passing = opts.get("pass")
        if passing is not None:     # each passed value as BT.CPP reads it, and the short form for the way back
            task = t.doc.get("task") or {}
            names = [k for k in child.params if k not in params and (k in t.params or k in task)] \
                if passing == "all" else list(passing)
            for k in names:
                el.set(k, ref_to_text(f"$param.{k}" if k in t.params else f"$task.{k}"))
            el.set(PASS_ATTR, "all" if passing == "all" else " ".join(names))
        remap = opts.get("remap") or {}
        for k, v in remap.items():
            if k in params or k in child.params:
                self._err(_vloc(remap, k), f"subtree {child.name!r}: {k!r} is both a parameter and a remapped key",
                          "BT.CPP has one port per name: rename the key")
                continue
            el.set(k, self._text(v, "any", _vloc(remap, k), f"remap of {k!r}"))
        for k in child.outputs:     # an output not remapped is the caller's key of the same name
            if k not in remap:
                el.set(k, "{" + k + "}")
        if opts.get("autoremap"):
            el.set("_autoremap", "true")
        return el

    # -- models ------------------------------------------------------------------------
    def _model(self) -> ET.Element:
        model = ET.Element("TreeNodesModel")
        for p in self.order:
            t = self.trees[p]
            sub = ET.SubElement(model, "SubTree", {"ID": t.id})
            for name, d in t.params.items():
                port = ET.SubElement(sub, "input_port", {"name": name, "type": str(d.get("type", "any"))})
                if "default" in d and d["default"] is not None:
                    port.set("default", self._text(d["default"], str(d.get("type", "any")), t.doc.loc,
                                                   f"default of parameter {name!r}"))
                elif "default" in d:
                    port.set("required", "false")
                if "required" in d:
                    port.set("required", "true" if d["required"] else "false")
                if d.get("choices"):
                    port.set("choices", json.dumps(_plain(d["choices"])))
                if d.get("doc"):
                    port.text = str(d["doc"])
            for name, d in t.outputs.items():
                port = ET.SubElement(sub, "output_port", {"name": name, "type": str(d.get("type", "any"))})
                if d.get("doc"):
                    port.text = str(d["doc"])
        for name in sorted(self.used):
            model.append(node_model(self.used[name]))
        return model


def node_model(nt: NodeType) -> ET.Element:
    """The TreeNodesModel entry of one rll-bt node type."""
    el = ET.Element(model_kind(nt), {"ID": nt.name})
    ports = list(nt.ports.values())
    for port in ports:
        tag = "output_port" if port.direction == "out" else "input_port"
        p = ET.SubElement(el, tag, {"name": port.name, "type": port.ptype.name})
        if port.direction == "in" and not port.required and port.default is not None:
            try:
                p.set("default", value_to_text(port.default, port.ptype.name))
            except ValueError_:
                pass
        if port.choices:
            p.set("choices", json.dumps(list(port.choices), default=str))
        if port.doc:
            p.text = port.doc
    for slot in nt.slots:
        if slot.expr:
            p = ET.SubElement(el, "input_port", {"name": slot.name, "type": "expr"})
            p.text = f"{slot.doc} (or a condition node as the first child)"
    if nt.summary:
        meta = ET.SubElement(el, "MetadataFields")
        ET.SubElement(meta, "Metadata", {"description": nt.summary})
    return el


def nodes_model(registry: NodeRegistry | None = None) -> str:
    """Every registered node type as a BT.CPP ``<TreeNodesModel>`` document."""
    reg = registry or default_registry()
    root = ET.Element("root", {"BTCPP_format": FORMAT})
    model = ET.SubElement(root, "TreeNodesModel")
    for name, nt in reg.types().items():
        if nt.kind == "subtree" or name in SAME:
            continue
        model.append(node_model(nt))
    return _text_of(root)


def export_xml(roots: Iterable[str | Path], registry: NodeRegistry | None = None,
               search_path: Iterable[str | Path] = ()) -> str:
    """YAML tree files (and every file they include) as one BT.CPP v4 XML
    document; the first root is ``main_tree_to_execute``.  Raises
    :class:`TreeLoadError` for a tree that does not load and
    :class:`ExportError` for a value BT.CPP cannot hold."""
    roots = list(roots)
    if not roots:
        raise ValueError("no tree files given")
    return _text_of(Writer(registry, search_path).document(roots))


def _text_of(root: ET.Element) -> str:
    ET.indent(root, space="  ")
    return '<?xml version="1.0" encoding="UTF-8"?>\n' + ET.tostring(root, encoding="unicode") + "\n"


def _split(value: Any, registry: NodeRegistry) -> tuple[str | None, dict]:
    """(type, ports and slots) of a node as written; a list stands for the first list slot."""
    if isinstance(value, str):
        return value, {}
    if isinstance(value, dict) and len(value) == 1:
        tname, opts = next(iter(value.items()))
        if opts is None:
            return tname, {}
        if isinstance(opts, list):
            nt = registry.get(tname)
            many = [s.name for s in nt.slots if s.many] if nt is not None else []
            return tname, {many[0] if many else "children": opts}
        return tname, opts
    return None, {}


def _vloc(opts: Any, key: str) -> Loc:
    return opts.vloc(key) if isinstance(opts, YMap) else getattr(opts, "loc", Loc("<tree>", 0, 0))


def _plain(value: Any) -> Any:
    if isinstance(value, dict):
        return {str(k): _plain(v) for k, v in value.items()}
    if isinstance(value, list):
        return [_plain(v) for v in value]
    if value is None or isinstance(value, (bool, int, float, str)):
        return value
    return str(value)
