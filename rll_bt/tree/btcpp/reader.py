"""BehaviorTree.CPP v4 XML back to YAML tree files.

Each ``<BehaviorTree>`` becomes one YAML file (at its ``_file`` path when
the document came from ``rll-bt tree export``, else ``<snake_id>.yaml``);
``<SubTree ID=...>`` becomes a ``subtree`` node naming that file, its
attributes the subtree's parameters (the ports its ``<SubTree>`` model
declares) or remapped keys (the rest); node elements become rll-bt node
types (BT.CPP built-ins through :mod:`.mapping`, others by their own name,
which must be a registered rll-bt type).  Children fill the node type's
slots in order: a ``recovery``'s first child is its action and the rest its
recoveries, a ``retry``'s second child its ``on_retry``, a ``guard``
without a ``condition`` attribute takes its condition node first.

Problems are reported as :class:`~rll_bt.tree.errors.TreeLoadError` with
``file:line`` of the XML.
"""
from __future__ import annotations

import json
import posixpath
import re
import xml.etree.ElementTree as ET
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any
from xml.parsers import expat

import yaml

from ..errors import Diagnostic, Loc, TreeLoadError, did_you_mean
from ..registry import NodeRegistry, NodeType, Slot, default_registry
from .mapping import BUILTINS, CONVERTED, FROM_BUILTIN, PASS_ATTR, ValueError_, snake, text_to_value

EXPLICIT = ("Action", "Condition", "Control", "Decorator")
_CPP_TYPES = {"std::string": "str", "string": "str", "double": "float", "float": "float", "int": "int",
              "unsigned": "int", "unsigned int": "int", "long": "int", "bool": "bool"}
_SAFE_PATH = re.compile(r"^[A-Za-z0-9_][A-Za-z0-9_./-]*\.yaml$")


def parse_xml(text: str, display: str) -> tuple[ET.Element, dict[int, int]]:
    """The root element and the line of every element (by ``id``).  Entity
    declarations are refused (no entity expansion, no external files)."""
    lines: dict[int, int] = {}
    builder = ET.TreeBuilder()
    p = expat.ParserCreate()
    p.SetParamEntityParsing(expat.XML_PARAM_ENTITY_PARSING_NEVER)

    def start(tag, attrs):
        el = builder.start(tag, attrs)
        lines[id(el)] = p.CurrentLineNumber

    def no_entities(name, *_):
        raise ValueError(f"entity declaration {name!r}")

    p.StartElementHandler = start
    p.EndElementHandler = builder.end
    p.CharacterDataHandler = builder.data
    p.EntityDeclHandler = no_entities
    try:
        p.Parse(text, True)
        root = builder.close()
    except expat.ExpatError as exc:
        raise TreeLoadError([Diagnostic(Loc(display, exc.lineno, exc.offset + 1), f"not well-formed XML: "
                                        f"{expat.ErrorString(exc.code)}", "check the XML syntax")]) from None
    except (ValueError, AssertionError) as exc:
        raise TreeLoadError([Diagnostic(Loc(display, p.CurrentLineNumber, 1), f"refused XML: {exc}",
                                        "tree files have no DTD or entities")]) from None
    return root, lines


@dataclass
class _Tree:
    id: str
    el: ET.Element
    file: str
    name: str
    params: dict[str, dict] = field(default_factory=dict)
    outputs: dict[str, dict] = field(default_factory=dict)


class Reader:
    def __init__(self, text: str, display: str = "<xml>", registry: NodeRegistry | None = None):
        self.display = display
        self.registry = registry or default_registry()
        self.root, self._lines = parse_xml(text, display)
        self.diags: list[Diagnostic] = []
        self.trees: dict[str, _Tree] = {}

    def _loc(self, el: ET.Element) -> Loc:
        return Loc(self.display, self._lines.get(id(el), 1), 1)

    def _err(self, el: ET.Element, message: str, hint: str = "") -> None:
        self.diags.append(Diagnostic(self._loc(el), message, hint))

    # -- document ------------------------------------------------------------------
    def read(self) -> dict[str, dict]:
        """{relative file path: YAML document (plain data)}, the main tree first."""
        r = self.root
        if r.tag != "root":
            self._err(r, f"the document's element is <{r.tag}>, not <root>", "a BT.CPP file starts with <root>")
            raise TreeLoadError(self.diags)
        if r.get("BTCPP_format") not in (None, "4"):
            self._err(r, f"BTCPP_format={r.get('BTCPP_format')!r}: only version 4 is read",
                      "convert the file with BT.CPP's v3-to-v4 converter first")
        for inc in r.findall("include"):
            self._err(inc, "<include> is not supported", "put every tree into one file (Groot2: save as one file)")
        models, outputs = {}, {}
        for m in r.findall("TreeNodesModel"):
            for sub in m.findall("SubTree"):
                models[sub.get("ID")] = self._params(sub, ("input_port", "inout_port"))
                outputs[sub.get("ID")] = self._params(sub, ("output_port",))
        files: set[str] = set()
        for i, el in enumerate(r.findall("BehaviorTree")):
            tid = el.get("ID") or f"BehaviorTree_{i}"
            f = el.get("_file") or ""
            if not _SAFE_PATH.match(f) or ".." in f.split("/"):
                if f:
                    self._err(el, f"_file={f!r} is not a relative .yaml path inside the folder; "
                              f"using {snake(tid)}.yaml", "")
                    self.diags.pop()        # only a note: fall back silently
                f = snake(tid) + ".yaml"
            if f in files:
                self._err(el, f"two trees would be written to {f}", "give the trees distinct IDs")
            files.add(f)
            self.trees[tid] = _Tree(tid, el, f, el.get("_name") or snake(tid), models.get(tid, {}),
                                    outputs.get(tid, {}))
        if not self.trees:
            self._err(r, "no <BehaviorTree> in the document", "")
        main = r.get("main_tree_to_execute") or (next(iter(self.trees)) if self.trees else None)
        if main is not None and main not in self.trees:
            self._err(r, f"main_tree_to_execute={main!r} names no <BehaviorTree>",
                      did_you_mean(main, self.trees, "trees"))
        if self.diags:
            raise TreeLoadError(self.diags)
        order = [main] + [t for t in self.trees if t != main]
        out = {}
        for tid in order:
            out[self.trees[tid].file] = self._tree(self.trees[tid])
        if self.diags:
            raise TreeLoadError(self.diags)
        return out

    def _params(self, sub: ET.Element, tags: tuple[str, ...]) -> dict[str, dict]:
        """The declarations of a ``<SubTree>`` model's ports of ``tags``
        (input ports: parameters; output ports: outputs)."""
        out = {}
        for port in list(sub):
            if port.tag not in tags or not port.get("name"):
                continue
            t = port.get("type", "any")
            t = _CPP_TYPES.get(t, t)
            try:
                from ..porttypes import port_type
                port_type(t)
            except (KeyError, TypeError):
                t = "any"
            d: dict[str, Any] = {"type": t}
            if port.text and port.text.strip():
                d["doc"] = port.text.strip()
            elif port.get("description"):
                d["doc"] = port.get("description")
            if port.get("default") is not None:
                d["default"] = self._value(port, port.get("default"), t, set())
            if port.get("required") is not None:
                d["required"] = port.get("required") == "true"
            if port.get("choices"):
                try:
                    d["choices"] = json.loads(port.get("choices"))
                except json.JSONDecodeError:
                    self._err(port, "choices is not a JSON list", "")
            out[port.get("name")] = d
        return out

    def _value(self, el: ET.Element, text: str, ptype: str, params: set[str]) -> Any:
        try:
            return text_to_value(text, ptype, params)
        except ValueError_ as exc:
            self._err(el, str(exc), "")
            return None

    def _tree(self, t: _Tree) -> dict:
        doc: dict[str, Any] = {"name": t.name}
        if t.el.get("_description"):
            doc["doc"] = t.el.get("_description")
        for section in ("task",):
            if t.el.get("_" + section):
                doc[section] = self._json(t.el, "_" + section)
        if t.params:
            doc["params"] = t.params
        if t.outputs:
            doc["outputs"] = {k: {x: v for x, v in d.items() if x not in ("default", "required")}
                              for k, d in t.outputs.items()}
        if t.el.get("_blackboard"):
            doc["blackboard"] = self._json(t.el, "_blackboard")
        kids = list(t.el)
        if len(kids) != 1:
            self._err(t.el, f"<BehaviorTree ID={t.id!r}> must have exactly one child, has {len(kids)}", "")
            return doc
        doc["root"] = self._node(t, kids[0])
        return doc

    def _json(self, el: ET.Element, attr: str) -> Any:
        try:
            return json.loads(el.get(attr))
        except json.JSONDecodeError as exc:
            self._err(el, f"{attr} is not JSON ({exc.msg})", "")
            return None

    # -- nodes -----------------------------------------------------------------------
    def _node(self, t: _Tree, el: ET.Element) -> Any:
        tag = el.tag
        if tag in EXPLICIT:
            tag = el.get("ID") or ""
        if tag == "SubTree":
            return self._subtree(t, el)
        tname = FROM_BUILTIN.get(tag, tag)
        nt = self.registry.get(tname)
        if nt is None or nt.kind == "subtree":
            hint = ("a BT.CPP built-in without an rll-bt equivalent" if tag in BUILTINS
                    else did_you_mean(tag, self.registry.names(), "node types") + "; `rll-bt tree nodes` lists them")
            self._err(el, f"unknown node type {tag!r}", hint)
            return tname
        params = set(t.params)
        opts: dict[str, Any] = {}
        attrs = dict(el.attrib)
        if el.tag in EXPLICIT:
            attrs.pop("ID", None)
        if "name" in attrs:
            opts["name"] = attrs.pop("name")
        if tag in CONVERTED:
            for bport, (port, scale) in CONVERTED[tag][1].items():
                if bport in attrs:
                    v = self._value(el, attrs.pop(bport), "float" if scale else "int", params)
                    opts[port] = v / scale if scale and isinstance(v, (int, float)) else v
        slot_attrs = {s.name for s in nt.slots if s.expr}
        for k, v in attrs.items():
            if k in slot_attrs:
                opts[k] = v
            elif k in nt.ports:
                opts[k] = self._value(el, v, nt.ports[k].ptype.name, params)
            elif k.startswith("_"):
                self._err(el, f"{k}: BT.CPP scripts and attributes starting with '_' are not supported", "")
            else:
                self._err(el, f"unknown port {k!r} for node type {tname!r}",
                          did_you_mean(k, nt.ports, "ports") if nt.ports else f"{tname} has no ports")
        slots = [s for s in nt.slots if not (s.expr and s.name in opts)]
        kids = [self._node(t, c) for c in el]
        for slot, value in _assign(slots, kids, lambda m: self._err(el, f"{tname}: {m}", "")).items():
            opts[slot] = value
        if not opts:
            return tname
        return {tname: opts}

    def _subtree(self, t: _Tree, el: ET.Element) -> Any:
        tid = el.get("ID") or ""
        target = self.trees.get(tid)
        if target is None:
            self._err(el, f"<SubTree ID={tid!r}>: no <BehaviorTree> with that ID in this document",
                      did_you_mean(tid, self.trees, "trees"))
            return "subtree"
        if len(el):
            self._err(el, "<SubTree> must not have children", "")
        opts: dict[str, Any] = {"file": posixpath.relpath(target.file, posixpath.dirname(t.file) or ".")}
        params, remap = {}, {}
        short = (el.get(PASS_ATTR) or "").split()
        passed: list[str] = []
        for k, v in el.attrib.items():
            if k in ("ID", PASS_ATTR):
                continue
            if v.strip() == "{=}":          # BT.CPP 4.10: the caller's entry of the same name
                v = "{" + k + "}"
            if k == "name":
                opts["name"] = v
            elif k == "_autoremap":
                opts["autoremap"] = v.strip().lower() == "true"
            elif k in target.params:
                value = self._value(el, v, str(target.params[k].get("type", "any")), set(t.params))
                if (short == ["all"] or k in short) and value == _same_name(k, t):
                    passed.append(k)
                else:
                    params[k] = value
            elif k in target.outputs:
                ref = self._value(el, v, "any", set(t.params))
                if ref != f"$bb.{k}":           # else the default: the caller's key of the same name
                    remap[k] = ref
            elif k.startswith("_"):
                self._err(el, f"{k}: not supported on <SubTree>", f"rll-bt reads _autoremap and {PASS_ATTR} there")
            else:
                ref = self._value(el, v, "any", set(t.params))
                if not (isinstance(ref, str) and ref.startswith("$bb.")):
                    self._err(el, f"{k}={v!r}: the subtree {tid!r} declares no port {k!r}, and a remapped key "
                              "must name a blackboard entry {KEY}",
                              f"declare it in <TreeNodesModel><SubTree ID=\"{tid}\">")
                remap[k] = ref
        if short == ["all"]:
            opts["pass"] = "all"
        elif passed:
            opts["pass"] = [k for k in short if k in passed]
        if params:
            opts["params"] = params
        if remap:
            opts["remap"] = remap
        return {"subtree": opts}


def _same_name(name: str, caller: _Tree) -> str:
    """What ``pass: [name]`` stands for in ``caller``: its parameter, else its task field."""
    return f"$param.{name}" if name in caller.params else f"$task.{name}"


def _assign(slots: list[Slot], kids: list, error) -> dict[str, Any]:
    """Children, in order, into slots (see the module doc)."""
    out: dict[str, Any] = {}
    i = 0
    for n, s in enumerate(slots):
        rest = slots[n + 1:]
        need_after = sum(1 for r in rest if r.required)
        avail = len(kids) - i
        if s.many:
            take = max(0, avail - sum(1 for r in rest if not r.many and r.required))
            if take or s.required:
                out[s.name] = kids[i:i + take]
            i += take
        elif s.required or avail > need_after:
            if avail <= 0:
                error(f"needs a child for `{s.name}`")
                continue
            out[s.name] = kids[i]
            i += 1
    if i < len(kids):
        error(f"{len(kids) - i} child(ren) too many")
    return out


def import_xml(text: str, display: str = "<xml>", registry: NodeRegistry | None = None) -> dict[str, str]:
    """BT.CPP XML as YAML texts: {relative file path: YAML text}, the main tree first."""
    docs = Reader(text, display, registry).read()
    return {path: dump_tree(doc) for path, doc in docs.items()}


def write_trees(texts: dict[str, str], out_dir: str | Path, force: bool = False) -> list[Path]:
    """Write :func:`import_xml`'s files under ``out_dir``; FileExistsError
    (nothing written) when one exists and ``force`` is false."""
    out = Path(out_dir)
    paths = [out / rel for rel in texts]
    existing = [p for p in paths if p.exists()]
    if existing and not force:
        raise FileExistsError(str(existing[0]))
    for p, text in zip(paths, texts.values()):
        p.parent.mkdir(parents=True, exist_ok=True)
        p.write_text(text, encoding="utf-8")
    return paths


class _Dumper(yaml.SafeDumper):
    pass


def _str(dumper, value: str):
    style = "|" if "\n" in value else None
    return dumper.represent_scalar("tag:yaml.org,2002:str", value, style=style)


_Dumper.add_representer(str, _str)


def dump_tree(doc: dict) -> str:
    """A tree document as YAML text."""
    return yaml.dump(doc, Dumper=_Dumper, sort_keys=False, allow_unicode=True, width=110,
                     default_flow_style=False)


__all__ = ["NodeType", "Reader", "dump_tree", "import_xml", "parse_xml", "write_trees"]
