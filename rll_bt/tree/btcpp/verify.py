"""Would BehaviorTree.CPP 4 accept this document?  The checks its XML parser
makes (``VerifyXML`` and tree creation), restated:

- the element is ``<root>`` with ``BTCPP_format="4"``; at most one
  ``<TreeNodesModel>``; ``main_tree_to_execute`` names a ``<BehaviorTree>``;
- every ``<BehaviorTree>`` has an ``ID`` (a valid model name, not a node
  type's) and exactly one child;
- ``<SubTree>`` has no children and an ``ID`` naming a tree of the document;
  its attributes are the ports of that tree's ``<SubTree>`` model (or
  remapped keys ``{KEY}``), ``name`` or ``_autoremap``; others whose names
  are not port names (``_pass``) are skipped;
- every other element is a built-in or a type declared in the model;
  Decorators have exactly one child, Controls at least one, Actions and
  Conditions none; ``Action``/``Condition``/``Control``/``Decorator``
  elements carry an ``ID``;
- attributes of a declared type are its ports (BT.CPP refuses a port it
  does not know), ``name``, or the pre/post-condition attributes.

:func:`problems` returns them as ``line: message`` strings (empty: accepted).
"""
from __future__ import annotations

import xml.etree.ElementTree as ET

from ..errors import TreeLoadError
from .mapping import BUILTIN_PORTS, BUILTINS, RESERVED, valid_model_name, valid_port_name
from .reader import EXPLICIT, parse_xml


def problems(text: str) -> list[str]:
    try:
        root, lines = parse_xml(text, "<xml>")
    except TreeLoadError as exc:
        return [str(d) for d in exc.diagnostics]
    out: list[str] = []

    def bad(el: ET.Element, msg: str) -> None:
        out.append(f"line {lines.get(id(el), 0)}: {msg}")

    if root.tag != "root":
        bad(root, "the XML must have a root node called <root>")
        return out
    if root.get("BTCPP_format") != "4":
        bad(root, "<root> must carry BTCPP_format=\"4\"")
    model_els = root.findall("TreeNodesModel")
    if len(model_els) > 1:
        bad(model_els[1], "only a single <TreeNodesModel> is supported")
    kinds: dict[str, str] = dict(BUILTINS)
    ports: dict[str, set[str] | None] = {k: BUILTIN_PORTS.get(k) for k in BUILTINS}
    subtree_ports: dict[str, set[str]] = {}
    for m in model_els:
        for el in m:
            mid = el.get("ID")
            if not mid:
                bad(el, f"<{el.tag}> in <TreeNodesModel> must have the attribute [ID]")
                continue
            names = set()
            for p in el:
                if p.tag in ("input_port", "output_port", "inout_port"):
                    pname = p.get("name")
                    if not pname:
                        bad(p, "missing attribute [name] in port")
                    elif not valid_port_name(pname):
                        bad(p, f"port name {pname!r} is not allowed")
                    else:
                        names.add(pname)
            if el.tag == "SubTree":
                subtree_ports[mid] = names
            elif el.tag in EXPLICIT:
                if not valid_model_name(mid):
                    bad(el, f"model name {mid!r} contains a forbidden character")
                if mid in BUILTINS:
                    bad(el, f"{mid!r} is a built-in node and cannot be declared again")
                kinds[mid] = el.tag
                ports[mid] = names
            else:
                bad(el, f"unexpected <{el.tag}> in <TreeNodesModel>")
    trees = root.findall("BehaviorTree")
    ids = [t.get("ID") for t in trees]
    if len(trees) > 1 and not all(ids):
        bad(trees[ids.index(None)], "the tag <BehaviorTree> must have the attribute [ID]")
    main = root.get("main_tree_to_execute")
    if main is not None and main not in ids:
        bad(root, f"main_tree_to_execute={main!r} names no <BehaviorTree>")
    for t in trees:
        tid = t.get("ID") or ""
        if tid and not valid_model_name(tid):
            bad(t, f"tree ID {tid!r} contains a forbidden character")
        if tid in kinds:
            bad(t, f"the ID {tid!r} of <BehaviorTree> must not be the name of a registered node")
        if len(t) != 1:
            bad(t, f"the <BehaviorTree> with ID {tid!r} must have exactly 1 child")
        for child in t:
            _node(child, kinds, ports, subtree_ports, set(ids), bad)
    return out


def _node(el, kinds, ports, subtree_ports, tree_ids, bad, depth: int = 0) -> None:
    if depth > 256:
        bad(el, "maximum XML nesting depth exceeded")
        return
    name = el.tag
    n = len(el)
    if name == "SubTree":
        sid = el.get("ID") or ""
        if not sid:
            bad(el, "<SubTree> must have the attribute [ID]")
        elif sid not in tree_ids:
            bad(el, f"<SubTree ID={sid!r}>: no <BehaviorTree> with that ID")
        if n:
            bad(el, f"<SubTree> with ID {sid!r} should not have any child")
        declared = subtree_ports.get(sid, set())
        for k, v in el.attrib.items():
            if k in ("ID", "name", "_autoremap") or k in declared or not k[:1].isalpha():
                continue                # BT.CPP skips a name that is not a port name (IsAllowedPortName)
            if not (v.startswith("{") and v.endswith("}")):
                bad(el, f"<SubTree ID={sid!r}>: {k}={v!r} is neither a declared port nor a remapped key")
        return
    lookup = el.get("ID") if name in ("Action", "Condition", "Control", "Decorator") else name
    if name in ("Action", "Condition", "Control", "Decorator") and not lookup:
        bad(el, f"the tag <{name}> must have the attribute [ID]")
        return
    kind = kinds.get(lookup)
    if kind is None:
        bad(el, f"node not recognized: {lookup}")
    elif kind == "Decorator" and n != 1:
        bad(el, f"the node {lookup!r} must have exactly 1 child")
    elif kind == "Control" and n == 0:
        bad(el, f"the node {lookup!r} must have 1 or more children")
    elif kind in ("Action", "Condition") and n:
        bad(el, f"the node {lookup!r} must not have any child")
    known = ports.get(lookup) if kind is not None else None
    if known is not None:
        for k in el.attrib:
            if k in RESERVED or (k == "ID" and lookup != name):
                continue
            if k not in known:
                bad(el, f"a port with name [{k}] is found in the XML, but not in the ports of {lookup!r}")
    for c in el:
        _node(c, kinds, ports, subtree_ports, tree_ids, bad, depth + 1)
