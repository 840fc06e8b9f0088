"""What a YAML tree means in BehaviorTree.CPP v4 XML, and back.

Node types: the rll-bt types that mean exactly what a BT.CPP built-in
means are written as that built-in (``sequence_with_memory`` is BT.CPP's
``Sequence``: it resumes a RUNNING child and starts again from the first
child after a failure); every other type keeps its rll-bt name and is
declared in ``<TreeNodesModel>``.  Four built-ins carry a unit or port name
of their own (``Timeout``/``Sleep`` take milliseconds, ``Repeat`` and
``RetryUntilSuccessful`` name their count differently); those are used only
when the rll-bt node's ports fit them exactly, else the rll-bt type is
written.

Values: ``$bb.KEY`` is the blackboard reference ``{KEY}`` and an absolute
``$bb./a/b`` the root-blackboard reference ``{@a/b}``; a tree parameter
``$param.NAME`` is the subtree port ``{NAME}`` (a BT.CPP SubTree's ports are
entries of its own blackboard); a task field ``$task.NAME`` is the root
entry ``{@task.NAME}`` (the dot keeps it apart from every rll-bt key).
Literals are text: strings as they are, numbers and booleans as YAML writes
them, lists and mappings (and strings that would read back as another type)
as ``json:`` followed by JSON, the prefix BT.CPP 4 uses for JSON values.

A subtree's ``pass:`` (parameters passed on by name) is written as the
values it stands for (``machine="{machine}"`` for a parameter of the
caller, ``machine="{@task.machine}"`` for a task field), so BT.CPP reads
what rll-bt means, plus ``_pass="machine side"`` (or ``_pass="all"``),
which BT.CPP skips (a name that is not a port name) and ``rll-bt tree
import`` turns back into the short form.  BT.CPP 4.10's own short form
``machine="{=}"`` (the caller's entry of the same name) is read too.
"""
from __future__ import annotations

import json
import re
from typing import Any

import yaml

FORMAT = "4"

#: rll-bt type -> BT.CPP built-in with the same meaning and no ports but ``name``
SAME = {
    "sequence_with_memory": "Sequence",
    "reactive_sequence": "ReactiveSequence",
    "selector_with_memory": "Fallback",
    "reactive_selector": "ReactiveFallback",
    "inverter": "Inverter",
    "force_success": "ForceSuccess",
    "force_failure": "ForceFailure",
    "success": "AlwaysSuccess",
    "failure": "AlwaysFailure",
}
#: BT.CPP built-in -> (rll-bt type, {BT.CPP port: (rll-bt port, scale)}): rll-bt value = BT.CPP value / scale
CONVERTED = {
    "Timeout": ("timeout", {"msec": ("seconds", 1000)}),
    "Sleep": ("wait", {"msec": ("seconds", 1000)}),
    "Repeat": ("repeat", {"num_cycles": ("count", None)}),
    "RetryUntilSuccessful": ("retry", {"num_attempts": ("attempts", None)}),
}
#: built-ins read as an rll-bt type although BT.CPP's behaviour differs a little
#: (SequenceWithMemory does not start again after a failure)
ALIASES = {"SequenceWithMemory": "sequence_with_memory", "SequenceStar": "sequence_with_memory"}
FROM_BUILTIN = {v: k for k, v in SAME.items()} | {k: v[0] for k, v in CONVERTED.items()} | ALIASES

#: every BT.CPP 4 built-in node and its kind (bt_factory.cpp), for checking documents
BUILTINS: dict[str, str] = {
    **dict.fromkeys((
        "Fallback", "AsyncFallback", "Sequence", "AsyncSequence", "SequenceWithMemory", "SequenceStar",
        "Parallel", "ParallelAll", "ReactiveSequence", "ReactiveFallback", "IfThenElse", "WhileDoElse",
        "TryCatch", "Switch2", "Switch3", "Switch4", "Switch5", "Switch6"), "Control"),
    **dict.fromkeys((
        "Inverter", "RetryUntilSuccessful", "KeepRunningUntilFailure", "Repeat", "Timeout", "Delay",
        "RunOnce", "ForceSuccess", "ForceFailure", "Precondition", "LoopInt", "LoopBool", "LoopDouble",
        "LoopString", "SkipUnlessUpdated", "WaitValueUpdate"), "Decorator"),
    **dict.fromkeys((
        "AlwaysSuccess", "AlwaysFailure", "Script", "SetBlackboard", "Sleep", "UnsetBlackboard",
        "WasEntryUpdated"), "Action"),
    "ScriptCondition": "Condition",
}
#: ports of the built-ins this module writes (others: not checked)
BUILTIN_PORTS = {"Timeout": {"msec"}, "Sleep": {"msec"}, "Repeat": {"num_cycles"},
                 "RetryUntilSuccessful": {"num_attempts"}, **{n: set() for n in SAME.values()}}
#: attribute names BT.CPP reserves on every node (pre/post conditions and the rest)
RESERVED = {"name", "ID", "_autoremap", "_failureIf", "_successIf", "_skipIf", "_while", "_onSuccess",
            "_onFailure", "_onHalted", "_post", "_uid", "_fullpath"}
_FORBIDDEN = set(" \t\n\r<>&\"'/\\:*?|.")
#: the attribute of a <SubTree> that keeps the YAML ``pass:`` short form
PASS_ATTR = "_pass"


def valid_model_name(name: str) -> bool:
    """Whether BT.CPP accepts ``name`` as a node type or tree ID."""
    return bool(name) and name not in ("Root", "root") and not any(
        c in _FORBIDDEN or ord(c) < 32 or ord(c) == 127 for c in name)


def valid_port_name(name: str) -> bool:
    return valid_model_name(name) and not name[0].isdigit() and name not in RESERVED


def model_kind(nodetype) -> str:
    """The TreeNodesModel element of an rll-bt node type: Action, Condition,
    Decorator (exactly one child slot) or Control (anything else with children)."""
    if nodetype.kind == "condition":
        return "Condition"
    if nodetype.kind == "action":
        return "Action"
    slots = [s for s in nodetype.slots if not s.expr]
    if nodetype.kind == "decorator" and len(slots) == 1 and not slots[0].many and slots[0].required \
            and not any(s.expr for s in nodetype.slots):
        return "Decorator"
    return "Control"


def camel(name: str) -> str:
    """``give_up`` -> ``GiveUp`` (tree IDs)."""
    return "".join(part[:1].upper() + part[1:] for part in re.split(r"[^A-Za-z0-9]+", name) if part) or "Tree"


def snake(name: str) -> str:
    """``GiveUp`` -> ``give_up``."""
    s = re.sub(r"(?<=[a-z0-9])([A-Z])", r"_\1", name)
    s = re.sub(r"[^A-Za-z0-9_]+", "_", s).strip("_").lower()
    return s if s and not s[0].isdigit() else f"tree_{s}"


# -- values ------------------------------------------------------------------------
_REF = re.compile(r"^\{(.*)\}$", re.DOTALL)
_YREF = re.compile(r"^\$(bb|task|param)\.\S+$")


class ValueError_(ValueError):
    """A value that has no BT.CPP spelling (or an attribute that is not a value)."""


def _reads_back(text: str) -> Any:
    try:
        return yaml.safe_load(text)
    except yaml.YAMLError:
        return text


def ref_to_text(ref: str) -> str:
    """A ``$bb``/``$param``/``$task`` reference as BT.CPP text."""
    kind, _, rest = ref[1:].partition(".")
    if kind == "bb":
        return "{@" + rest[1:] + "}" if rest.startswith("/") else "{" + rest + "}"
    if kind == "param":
        return "{" + rest + "}"
    if kind == "task":
        return "{@task." + rest + "}"
    raise ValueError_(f"unknown reference {ref!r}")


def text_to_ref(text: str, params: set[str]) -> str | None:
    """``{...}`` as an rll-bt reference (``params``: the tree's parameters);
    None when ``text`` is not a blackboard reference."""
    m = _REF.match(text)
    if not m:
        return None
    body = m.group(1).strip()
    if body.startswith("@task."):
        return "$task." + body[len("@task."):]
    if body.startswith("@"):
        return "$bb./" + body[1:]
    if body in params:
        return "$param." + body
    return "$bb." + body


def value_to_text(value: Any, ptype: str) -> str:
    """A YAML port value as an XML attribute value (see the module doc);
    ``ptype`` "expr" is a condition, written as it is."""
    if ptype == "expr":
        if not isinstance(value, str):
            raise ValueError_(f"a condition must be text, not {value!r}")
        if _REF.match(value):
            raise ValueError_(f"the condition {value!r} would read as a blackboard reference in BT.CPP")
        return value
    if isinstance(value, str) and value.startswith("$"):
        if value.startswith("$$"):
            return value[1:]
        if not _YREF.match(value):
            raise ValueError_(f"{value!r} is not a reference ($bb.KEY, $param.NAME, $task.NAME)")
        return ref_to_text(value)
    if isinstance(value, str) and _REF.match(value):
        raise ValueError_(f"the text {value!r} would read as a blackboard reference in BT.CPP")
    if ptype == "str":
        if not isinstance(value, str) or value.startswith("json:"):
            return "json:" + json.dumps(value)
        return value
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, (int, float)) and not isinstance(value, bool):
        text = repr(value)
        if _reads_back(text) == value and type(_reads_back(text)) is type(value):
            return text
        return "json:" + json.dumps(value)
    if isinstance(value, str) and not value.startswith("json:") and _reads_back(value) == value \
            and not (ptype.startswith("list") and ";" in value):       # BT.CPP's a;b;c would split it
        return value
    return "json:" + json.dumps(value)


def text_to_value(text: str, ptype: str, params: set[str]) -> Any:
    """An XML attribute value as a YAML port value (``ptype`` "expr": a condition)."""
    if ptype == "expr":
        return text
    ref = text_to_ref(text, params)
    if ref is not None:
        return ref
    if text.startswith("json:"):
        try:
            value = json.loads(text[5:])
        except json.JSONDecodeError as exc:
            raise ValueError_(f"bad JSON after json: ({exc.msg})") from None
    elif ptype in ("str", "expr"):
        value = text
    elif ptype.startswith("list") and ";" in text:
        value = [_reads_back(p) if ptype != "list[str]" else p for p in text.split(";")]   # BT.CPP's a;b;c
    else:
        value = _reads_back(text)
    if isinstance(value, str) and value.startswith("$"):
        return "$" + value
    return value
