"""Values written in a tree file, bound to ports: literals, ``$task.NAME``,
``$param.NAME``, ``$bb.KEY`` and conditions.

:class:`Binder` resolves a reference in the instance (:class:`~.files.Instance`)
it is written in, checks a value against the port it feeds and records the
blackboard keys read and written in the :class:`~.keys.KeyBook`.
"""
from __future__ import annotations

import re
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from .errors import Loc, did_you_mean
from .expr import ExprError, parse_expr
from .files import Instance, Report, TreeFile, check_value, valid_key
from .keys import KeyBook
from .ports import Binding, Const, Key, Port, Unknown
from .porttypes import EXPR, PortTypeError, port_type
from .source import YList, YMap
from .spec import Decl

#: a whole value that is one $task/$param reference (for a condition: the text it holds)
_WHOLE_REF = re.compile(r"^\$(task|param)\.[A-Za-z_][A-Za-z0-9_]*$")


class Binder:
    """``task=None`` leaves ``$task.NAME`` symbolic (checking without a task);
    ``strict`` demands every required task field."""

    def __init__(self, report: Report, keys: KeyBook, task: Mapping[str, Any] | None, strict: bool):
        self.report = report
        self.keys = keys
        self.task = None if task is None else dict(task)
        self.strict = strict
        self._task_values: dict[tuple[Path, str], Binding] = {}

    # -- task fields -------------------------------------------------------------
    def task_field(self, f: TreeFile, name: str, decl: Decl, text: str) -> Binding:
        cache_key = (f.path, name)
        if cache_key in self._task_values:
            return self._task_values[cache_key]
        if self.task is None:
            b: Binding = Unknown(decl.ptype, text)
        elif name in self.task:
            try:
                b = Const(check_value(decl, self.task[name]), text)
            except PortTypeError as exc:
                self.report(decl.loc, f"task field {name!r}: {exc}", f"the task must give {name} as {decl.ptype.name}")
                b = Unknown(decl.ptype, text)
        elif decl.required:
            if self.strict:
                self.report(decl.loc, f"the task does not give the required field {name!r}",
                            f"pass it: --task {name}=VALUE (or give it a default)")
            b = Unknown(decl.ptype, text)
        else:
            b = Const(decl.default, text)
        self._task_values[cache_key] = b
        return b

    # -- references ------------------------------------------------------------
    def ref(self, text: str, loc: Loc, env: Instance) -> Binding | None:
        """``$task.NAME``, ``$param.NAME`` or ``$bb.KEY`` in ``env`` (None after reporting)."""
        kind, _, rest = text[1:].partition(".")
        if kind == "task":
            decl = env.file.task.get(rest)
            if decl is None:
                self.report(loc, f"unknown task field {rest!r} in {text}",
                            (did_you_mean(rest, env.file.task, "task fields") + "; " if env.file.task else "")
                            + f"declare it: task: {{{rest}: {{type: str}}}}")
                return None
            return self.task_field(env.file, rest, decl, text)
        if kind == "param":
            if rest not in env.file.params:
                self.report(loc, f"unknown parameter {rest!r} in {text}",
                            (did_you_mean(rest, env.file.params, "parameters") + "; " if env.file.params else "")
                            + f"declare it: params: {{{rest}: {{type: str}}}}")
                return None
            return env.params.get(rest, Unknown(env.file.params[rest].ptype, text))
        if kind == "bb":
            if not valid_key(rest):
                self.report(loc, f"{rest!r} is not a valid blackboard key",
                            "keys are names of letters, digits and '_', joined by '/'; a leading '/' is absolute")
                return None
            return Key(env.key(rest), text)
        self.report(loc, f"unknown reference {text!r}",
                    "use $task.NAME, $param.NAME or $bb.KEY; write $$ for a text that starts with $")
        return None

    def substitute(self, value: Any, loc: Loc, env: Instance) -> tuple[Any, bool]:
        """Replace $task/$param inside a literal list or mapping.  Returns
        (value, known); ``known`` is False when a part has no value yet."""
        if isinstance(value, str) and value.startswith("$"):
            if value.startswith("$$"):
                return value[1:], True
            b = self.ref(value, loc, env)
            if b is None:
                return None, False
            if isinstance(b, Key):
                self.report(loc, f"{value} inside a list or mapping", "a blackboard reference must be the whole "
                            "value of a port; put the list itself on the blackboard")
                return None, False
            if isinstance(b, Unknown):
                return None, False
            return b.value, True
        if isinstance(value, list):
            out, known = [], True
            for i, item in enumerate(value):
                v, k = self.substitute(item, value.iloc(i) if isinstance(value, YList) else loc, env)
                out.append(v)
                known = known and k
            return out, known
        if isinstance(value, dict):
            out_d, known = {}, True
            for key, item in value.items():
                v, k = self.substitute(item, value.vloc(key) if isinstance(value, YMap) else loc, env)
                out_d[key] = v
                known = known and k
            return out_d, known
        return value, True

    # -- ports -------------------------------------------------------------------
    def bind(self, port: Port, value: Any, loc: Loc, env: Instance, owner: str) -> Binding | None:
        """``value`` as written for ``port`` of ``owner`` (None after reporting)."""
        label = f"port {port.name!r} of {owner}"
        source = None
        if port.ptype is EXPR and isinstance(value, str) and not _WHOLE_REF.match(value):
            return self.expr(value, loc, env, label)     # a condition, even one starting with $task.
        if isinstance(value, str) and value.startswith("$") and not value.startswith("$$"):
            b = self.ref(value, loc, env)
            if b is None:
                return None
            if isinstance(b, Key):
                if port.constant:
                    self.report(loc, f"{label} takes a value fixed when the tree loads, not a blackboard key",
                                "write a literal, $task.NAME or $param.NAME")
                    return None
                (self.keys.read if port.direction == "in" else self.keys.write)(b.key, port.ptype, loc, label)
                return b
            if port.direction == "out":
                self.report(loc, f"output {label} must be bound to a blackboard key, not {value}",
                            f"write `{port.name}: $bb.some_key`")
                return None
            if isinstance(b, Unknown):
                if not port.ptype.accepts(b.ptype):
                    self.report(loc, f"{label} expects {port.ptype.name} but {value} is {b.ptype.name}",
                                f"declare {value} as {port.ptype.name}, or bind another value")
                    return None
                return b
            value, source = b.value, value
        if port.direction == "out":
            self.report(loc, f"output {label} must be bound to a blackboard key", f"write `{port.name}: $bb.some_key`")
            return None
        if port.ptype is EXPR:
            return self.expr(value, loc, env, label, source)
        value, known = self.substitute(value, loc, env)
        if not known:
            return Unknown(port.ptype, source or str(value))
        if value is None and not port.required:
            return Const(port.default, "null")
        try:
            return Const(port.check(value), source if source is not None else show(value))
        except PortTypeError as exc:
            hint = f"give a {port.ptype.name}" + (f" such as {port.default!r}" if port.default is not None else "")
            if port.choices:
                hint = did_you_mean(str(value), map(str, port.choices), "choices")
            self.report(loc, f"{label}: {exc}", hint + "; or bind it to a blackboard key with $bb.KEY"
                        if not port.constant else hint)
            return None

    def expr(self, text: Any, loc: Loc, env: Instance, label: str, source: str | None = None) -> Binding | None:
        """A condition, parsed (never evaluated) with its keys and references resolved in ``env``."""
        if not isinstance(text, str):
            self.report(loc, f"{label}: a condition must be text, got {type(text).__name__}",
                        "write the condition as text, e.g. \"attempts < 3\"")
            return None

        def resolve_ref(ref: str, pos: int):
            b = self.ref(ref, loc.shifted(pos), env)
            if b is None:
                raise ExprError(f"bad reference {ref}", pos, "see the error above")
            if isinstance(b, Key):
                return ("key", b.key)
            if isinstance(b, Unknown):
                return ("const", None)
            return ("const", b.value)
        try:
            e = parse_expr(text, env.key, resolve_ref)
        except ExprError as exc:
            if exc.message.startswith("bad reference"):
                return None
            self.report(loc.shifted(exc.offset), f"{label}: {exc.message} in condition {text!r}", exc.hint)
            return None
        for k in e.keys:
            self.keys.read(k, port_type("any"), loc, label)
        return Const(e, source or text)


def show(value: Any) -> str:
    """A literal as YAML would write it (the ``source`` of a binding)."""
    if isinstance(value, str):
        return value
    if isinstance(value, bool):
        return "true" if value else "false"
    if value is None:
        return "null"
    return repr(value)
