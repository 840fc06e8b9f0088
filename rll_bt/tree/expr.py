"""A small, safe condition language for guards and ``check_blackboard``.

Grammar (no calls, no attributes, no arithmetic, nothing is ever evaluated
as Python)::

    expr    := or
    or      := and ("or" and)*
    and     := not ("and" not)*
    not     := "not" not | compare
    compare := operand (("=="|"!="|"<"|"<="|">"|">="|"in"|"not in") operand)?
    operand := literal | key | "$task.NAME" | "$param.NAME" | "$bb.KEY" | "(" expr ")" | "[" literals "]"
    literal := number | 'text' | "text" | true | false | null
    key     := name ("/" name)*  or  "/" name ("/" name)*     (a blackboard key)

A key that is not on the blackboard reads as ``null``.  An ordering
comparison between values that cannot be ordered (``null < 3``) is false.
"""
from __future__ import annotations

import operator
import re
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

KEYWORDS = {"and", "or", "not", "in", "true", "false", "null", "True", "False", "None"}
_CONST_WORDS = {"true": True, "True": True, "false": False, "False": False, "null": None, "None": None}

_TOKEN = re.compile(r"""
    (?P<ws>\s+)
  | (?P<num>-?(?:\d+\.\d*|\.\d+|\d+)(?:[eE][-+]?\d+)?)
  | (?P<str>'(?:[^'\\]|\\.)*'|"(?:[^"\\]|\\.)*")
  | (?P<ref>\$(?:[A-Za-z_][A-Za-z0-9_]*)\.[A-Za-z0-9_/]+)
  | (?P<name>/?[A-Za-z_][A-Za-z0-9_]*(?:/[A-Za-z_][A-Za-z0-9_]*)*)
  | (?P<op>==|!=|<=|>=|<|>|\(|\)|\[|\]|,)
""", re.VERBOSE)

_CMP = {"==": operator.eq, "!=": operator.ne, "<": operator.lt, "<=": operator.le,
        ">": operator.gt, ">=": operator.ge}


class ExprError(ValueError):
    """A condition that cannot be parsed; ``offset`` is the character index."""

    def __init__(self, message: str, offset: int, hint: str = ""):
        super().__init__(message)
        self.message = message
        self.offset = offset
        self.hint = hint or ("conditions are comparisons of blackboard keys and literals joined with "
                             "and/or/not, e.g. `holding == true and attempts < 3`")


@dataclass
class _Tok:
    kind: str
    text: str
    pos: int


def _tokenise(text: str) -> list[_Tok]:
    out, pos = [], 0
    while pos < len(text):
        m = _TOKEN.match(text, pos)
        if m is None:
            ch = text[pos]
            hint = ""
            if ch == ".":
                hint = "attribute access is not allowed; blackboard keys use '/' (e.g. gripper/holding)"
            elif ch in "+-*/%":
                hint = "arithmetic is not part of the condition language; compute the value in a node"
            raise ExprError(f"unexpected character {ch!r}", pos, hint)
        kind = m.lastgroup
        if kind != "ws":
            out.append(_Tok(kind, m.group(), pos))
        pos = m.end()
    out.append(_Tok("end", "", len(text)))
    return out


# AST: tuples ("const", v) | ("key", abs_key) | ("cmp", op, a, b) | ("in", a, b, negate)
#      | ("and", a, b) | ("or", a, b) | ("not", a) | ("list", [nodes])
class _Parser:
    def __init__(self, text: str, resolve_key: Callable[[str], str], resolve_ref: Callable[[str, int], Any]):
        self.text = text
        self.toks = _tokenise(text)
        self.i = 0
        self.resolve_key = resolve_key
        self.resolve_ref = resolve_ref

    def peek(self) -> _Tok:
        return self.toks[self.i]

    def take(self) -> _Tok:
        t = self.toks[self.i]
        self.i += 1
        return t

    def expect(self, text: str) -> None:
        t = self.take()
        if t.text != text:
            raise ExprError(f"expected {text!r} but found {t.text or 'the end'!r}", t.pos)

    def parse(self):
        if self.peek().kind == "end":
            raise ExprError("empty condition", 0)
        node = self.or_()
        t = self.peek()
        if t.kind != "end":
            raise ExprError(f"unexpected {t.text!r} after a complete condition", t.pos,
                            "join conditions with `and`/`or`")
        return node

    def or_(self):
        node = self.and_()
        while self.peek().text == "or":
            self.take()
            node = ("or", node, self.and_())
        return node

    def and_(self):
        node = self.not_()
        while self.peek().text == "and":
            self.take()
            node = ("and", node, self.not_())
        return node

    def not_(self):
        if self.peek().text == "not":
            self.take()
            return ("not", self.not_())
        return self.compare()

    def compare(self):
        left = self.operand()
        t = self.peek()
        if t.kind == "op" and t.text in _CMP:
            self.take()
            return ("cmp", t.text, left, self.operand())
        if t.text == "in":
            self.take()
            return ("in", left, self.operand(), False)
        if t.text == "not" and self.toks[self.i + 1].text == "in":
            self.i += 2
            return ("in", left, self.operand(), True)
        return left

    def operand(self):
        t = self.take()
        if t.kind == "num":
            return ("const", float(t.text) if any(c in t.text for c in ".eE") else int(t.text))
        if t.kind == "str":
            body = t.text[1:-1]
            return ("const", re.sub(r"\\(.)", r"\1", body))
        if t.kind == "ref":
            return self.resolve_ref(t.text, t.pos)
        if t.kind == "name":
            if t.text in _CONST_WORDS:
                return ("const", _CONST_WORDS[t.text])
            if t.text in KEYWORDS:
                raise ExprError(f"{t.text!r} cannot start an operand", t.pos)
            nxt = self.peek()
            if nxt.text == "(":
                raise ExprError(f"function calls are not allowed ({t.text}(...))", nxt.pos,
                                "conditions compare blackboard keys and literals; they call nothing")
            if any(seg.startswith("__") for seg in t.text.strip("/").split("/")):
                raise ExprError(f"{t.text!r} is not a valid blackboard key", t.pos,
                                "keys may not start with '__'")
            return ("key", self.resolve_key(t.text))
        if t.text == "(":
            node = self.or_()
            self.expect(")")
            return node
        if t.text == "[":
            items = []
            if self.peek().text != "]":
                while True:
                    items.append(self.operand())
                    if self.peek().text == ",":
                        self.take()
                        continue
                    break
            self.expect("]")
            return ("list", items)
        raise ExprError(f"expected a value but found {t.text or 'the end'!r}", t.pos)


def _ordered(op):
    def cmp(a, b):
        try:
            return op(a, b)
        except TypeError:
            return False
    return cmp


_SAFE_CMP = {k: (v if k in ("==", "!=") else _ordered(v)) for k, v in _CMP.items()}


class Expr:
    """A parsed condition.  ``keys`` are the absolute blackboard keys it reads;
    ``bind(blackboard)`` gives a zero-argument function evaluating it."""

    def __init__(self, source: str, ast):
        self.source = source
        self.ast = ast
        keys: list[str] = []
        self._collect(ast, keys)
        self.keys = tuple(dict.fromkeys(keys))

    def _collect(self, node, keys) -> None:
        tag = node[0]
        if tag == "key":
            keys.append(node[1])
        elif tag == "cmp":
            self._collect(node[2], keys)
            self._collect(node[3], keys)
        elif tag in ("and", "or") or tag == "in":
            self._collect(node[1], keys)
            self._collect(node[2], keys)
        elif tag == "not":
            self._collect(node[1], keys)
        elif tag == "list":
            for n in node[1]:
                self._collect(n, keys)

    def bind(self, blackboard) -> Callable[[], Any]:
        data = blackboard._data
        return _compile(self.ast, data)

    def evaluate(self, blackboard) -> bool:
        return bool(self.bind(blackboard)())

    def __repr__(self) -> str:
        return f"Expr({self.source!r})"

    def __str__(self) -> str:
        return self.source


def _compile(node, data: dict) -> Callable[[], Any]:
    tag = node[0]
    if tag == "const":
        v = node[1]
        return lambda: v
    if tag == "key":
        k, get = node[1], data.get
        return lambda: get(k)
    if tag == "list":
        items = [_compile(n, data) for n in node[1]]
        return lambda: [f() for f in items]
    if tag == "cmp":
        op, a, b = _SAFE_CMP[node[1]], _compile(node[2], data), _compile(node[3], data)
        return lambda: op(a(), b())
    if tag == "in":
        a, b, neg = _compile(node[1], data), _compile(node[2], data), node[3]

        def contains():
            try:
                r = a() in b()
            except TypeError:
                r = False
            return (not r) if neg else r
        return contains
    if tag == "and":
        a, b = _compile(node[1], data), _compile(node[2], data)
        return lambda: bool(a()) and bool(b())
    if tag == "or":
        a, b = _compile(node[1], data), _compile(node[2], data)
        return lambda: bool(a()) or bool(b())
    if tag == "not":
        a = _compile(node[1], data)
        return lambda: not a()
    raise AssertionError(tag)


def parse_expr(text: str, resolve_key: Callable[[str], str] | None = None,
               resolve_ref: Callable[[str, int], Any] | None = None) -> Expr:
    """Parse ``text``.  ``resolve_key(name)`` maps a key as written to an
    absolute key (default: prefix ``/``); ``resolve_ref(ref, offset)`` maps a
    ``$kind.name`` reference to an AST node (``("const", v)`` or
    ``("key", k)``) or raises :class:`ExprError`."""
    if not isinstance(text, str):
        raise ExprError(f"a condition must be text, not {type(text).__name__}", 0)
    rk = resolve_key or (lambda k: k if k.startswith("/") else "/" + k)

    def default_ref(ref: str, pos: int):
        if ref.startswith("$bb."):
            return ("key", rk(ref[4:]))
        raise ExprError(f"{ref} cannot be used here", pos)
    return Expr(text, _Parser(text, rk, resolve_ref or default_ref).parse())
