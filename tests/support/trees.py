"""Shared helpers for the tree engine tests: a probe node type that follows
a scripted list of statuses and records its life cycle."""
from __future__ import annotations

import textwrap

import pytest

from rll_bt.clock import SimClock
from rll_bt.tree import Input, Node, RunContext, Status, default_registry, load_tree, parse_tree

_CODES = {"S": Status.SUCCESS, "F": Status.FAILURE, "R": Status.RUNNING}


class Probe(Node):
    """Test action: returns ``script`` statuses in turn (the last repeats)
    and records initialise/update/terminate in ctx.services['events']."""
    tag = Input(str, "label used in the event log")
    script = Input(str, "statuses, e.g. RRS", default="S")

    def initialise(self):
        self._i = 0
        self.ctx.services["events"].append(f"{self.tag}:start")

    def update(self):
        s = self.script
        code = s[min(self._i, len(s) - 1)]
        self._i += 1
        return _CODES[code]

    def terminate(self, new_status):
        self.ctx.services["events"].append(f"{self.tag}:{'halt' if new_status is Status.INVALID else 'end'}")


class Flag(Node):
    """Test condition: SUCCESS when the blackboard key ``key`` is true."""
    kind = "condition"
    key = Input(object, "the value to test")

    def update(self):
        return Status.SUCCESS if self.key else Status.FAILURE


@pytest.fixture
def registry():
    reg = default_registry().child()
    reg.register(Probe, "probe")
    reg.register(Flag, "flag")
    return reg


@pytest.fixture
def clock():
    return SimClock()


def _write(tmp_path, text, files, name):
    for fname, body in (files or {}).items():
        p = tmp_path / fname
        p.parent.mkdir(parents=True, exist_ok=True)
        p.write_text(textwrap.dedent(body))
    path = tmp_path / name
    path.write_text(textwrap.dedent(text))
    return path


@pytest.fixture
def make(tmp_path, registry, clock):
    """make(yaml_text, task=..., files={name: text}) -> (tree, events)"""
    def _make(text, task=None, params=None, files=None, name="tree.yaml"):
        path = _write(tmp_path, text, files, name)
        events: list[str] = []
        ctx = RunContext(clock=clock, task=task or {}, services={"events": events})
        tree = load_tree(path, task=task or {}, params=params, ctx=ctx, registry=registry)
        return tree, events
    return _make


@pytest.fixture
def check(tmp_path, registry):
    """check(yaml_text, files=...) -> list of error strings (empty when valid)."""
    from rll_bt.tree import TreeLoadError

    def _check(text, files=None, name="tree.yaml", task=None):
        path = _write(tmp_path, text, files, name)
        try:
            parse_tree(path, registry=registry, task=task, strict=task is not None)
        except TreeLoadError as exc:
            return [str(d) for d in exc.diagnostics]
        return []
    return _check


def tick_n(tree, n):
    for _ in range(n):
        tree.tick()
    return tree.status
