"""Read YAML with ``yaml.safe_load`` semantics, keeping where every value was.

Mappings become :class:`YMap` (a dict with the location of each key and
value), sequences :class:`YList`; scalars are plain Python values built by
PyYAML's ``SafeConstructor``, so nothing but plain data is ever created:
tags such as ``!!python/object`` are refused.  Duplicate keys are errors.
"""
from __future__ import annotations

import yaml
from yaml.nodes import MappingNode, ScalarNode, SequenceNode

from .errors import Diagnostic, Loc

_MAP_TAGS = {"tag:yaml.org,2002:map"}
_SEQ_TAGS = {"tag:yaml.org,2002:seq"}


class YMap(dict):
    """A mapping read from YAML: ``loc`` of the mapping, ``key_locs`` and
    ``value_locs`` per key."""
    __slots__ = ("loc", "key_locs", "value_locs")

    def __init__(self, loc: Loc):
        super().__init__()
        self.loc = loc
        self.key_locs: dict = {}
        self.value_locs: dict = {}

    def vloc(self, key) -> Loc:
        return self.value_locs.get(key, self.key_locs.get(key, self.loc))

    def kloc(self, key) -> Loc:
        return self.key_locs.get(key, self.loc)


class YList(list):
    """A sequence read from YAML with ``loc`` and ``item_locs``."""
    __slots__ = ("loc", "item_locs")

    def __init__(self, loc: Loc):
        super().__init__()
        self.loc = loc
        self.item_locs: list[Loc] = []

    def iloc(self, i: int) -> Loc:
        return self.item_locs[i] if i < len(self.item_locs) else self.loc


class SourceError(Exception):
    """The text is not acceptable YAML for a tree."""

    def __init__(self, diagnostic: Diagnostic):
        super().__init__(str(diagnostic))
        self.diagnostic = diagnostic


class _Loader(yaml.SafeLoader):
    """SafeLoader that only composes; we construct with marks ourselves."""


def _loc(filename: str, node) -> Loc:
    m = node.start_mark
    style = getattr(node, "style", None) if isinstance(node, ScalarNode) else None
    return Loc(filename, m.line + 1, m.column + 1, style)


def _hint_for_yaml(problem: str) -> str:
    p = problem.lower()
    if "\\t" in problem or "\t" in problem:
        return "YAML forbids tabs for indentation: indent with spaces"
    if "constructor for the tag" in p or "tag" in p:
        return "tree files are plain YAML: tags such as !!python/object are refused; remove the tag"
    if "mapping values are not allowed" in p:
        return ("check the indentation of this line, or quote a value that contains ': '")
    if "expected <block end>" in p or "block mapping" in p or "block collection" in p \
            or "expected ':'" in p or "could not find expected" in p or "expected '-'" in p:
        return "check the indentation: the items of one list or mapping must start in the same column"
    if "found undefined alias" in p:
        return "define the anchor (&name) before using the alias (*name)"
    return "fix the YAML syntax at this place"


def parse_yaml(text: str, filename: str):
    """Parse one YAML document; return the located value (``None`` when empty).

    Raises :class:`SourceError` with ``file:line:col`` for syntax errors,
    refused tags and duplicate keys.
    """
    loader = None
    try:
        loader = _Loader(text)            # its reader already refuses control characters
        node = loader.get_single_node()
        if node is None:
            return None
        return _convert(loader, node, filename, set())
    except yaml.MarkedYAMLError as exc:
        mark = exc.problem_mark or exc.context_mark
        loc = Loc(filename, mark.line + 1, mark.column + 1) if mark else Loc(filename, 1, 1)
        problem = exc.problem or exc.context or "invalid YAML"
        if exc.context and exc.problem:
            problem = f"{exc.context}, {exc.problem}"
        raise SourceError(Diagnostic(loc, f"YAML: {problem}", _hint_for_yaml(problem))) from None
    except yaml.YAMLError as exc:
        raise SourceError(Diagnostic(Loc(filename, 1, 1), f"YAML: {exc}",
                                     "fix the YAML syntax")) from None
    finally:
        if loader is not None:
            loader.dispose()


def _convert(loader: _Loader, node, filename: str, active: set):
    loc = _loc(filename, node)
    if isinstance(node, ScalarNode):
        return loader.construct_object(node, deep=True)
    if id(node) in active:
        raise SourceError(Diagnostic(loc, "recursive YAML alias", "an alias may not refer to a node that contains it"))
    active.add(id(node))
    try:
        if isinstance(node, MappingNode):
            if node.tag not in _MAP_TAGS:
                raise SourceError(Diagnostic(loc, f"YAML tag {node.tag!r} is not allowed",
                                             _hint_for_yaml("tag")))
            loader.flatten_mapping(node)
            out = YMap(loc)
            for knode, vnode in node.value:
                if not isinstance(knode, ScalarNode):
                    raise SourceError(Diagnostic(_loc(filename, knode), "mapping keys must be plain scalars",
                                                 "write the key as a word, e.g. `name:`"))
                key = loader.construct_object(knode, deep=True)
                try:
                    hash(key)
                except TypeError:
                    raise SourceError(Diagnostic(_loc(filename, knode), "unhashable mapping key",
                                                 "write the key as a word")) from None
                if key in out:
                    first = out.key_locs[key]
                    raise SourceError(Diagnostic(_loc(filename, knode),
                                                 f"duplicate key {key!r} (first at line {first.line})",
                                                 "each key may appear once in a mapping; check the indentation"))
                out.key_locs[key] = _loc(filename, knode)
                out.value_locs[key] = _loc(filename, vnode)
                out[key] = _convert(loader, vnode, filename, active)
            return out
        if isinstance(node, SequenceNode):
            if node.tag not in _SEQ_TAGS:
                raise SourceError(Diagnostic(loc, f"YAML tag {node.tag!r} is not allowed",
                                             _hint_for_yaml("tag")))
            out = YList(loc)
            for item in node.value:
                out.item_locs.append(_loc(filename, item))
                out.append(_convert(loader, item, filename, active))
            return out
        raise SourceError(Diagnostic(loc, "unsupported YAML node", "use plain mappings, lists and scalars"))
    finally:
        active.discard(id(node))
