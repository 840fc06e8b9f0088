"""Retry (delay, backoff, attempt hook, on_retry), timeout, repeat,
inverter, force_*, one_shot and guard, on a simulated clock."""
import pytest

from rll_bt.tree import Status
from tests.support.trees import tick_n


def test_retry_waits_with_backoff_on_the_context_clock(make, clock):
    tree, ev = make("""
        root:
          retry:
            attempts: 4
            delay: 1.0
            backoff: 2.0
            attempt: $bb.attempt
            child: {probe: {tag: try, script: F}}
        """)
    starts = []
    seen = 0
    status = Status.RUNNING
    while status is Status.RUNNING and clock.now() < 30:
        status = tree.tick()
        if ev.count("try:start") > seen:
            seen = ev.count("try:start")
            starts.append(round(clock.now(), 2))
        clock.advance(0.01)
    assert status is Status.FAILURE
    gaps = [b - a for a, b in zip(starts, starts[1:])]    # each attempt fails in the tick it starts
    for gap, want in zip(gaps, (1.0, 2.0, 4.0), strict=True):  # waits of 1, 2, 4 s, within one tick
        assert want - 1e-9 <= gap <= want + 0.011
    assert tree.blackboard.get("/attempt") == 4


def test_retry_max_delay_and_success(make, clock):
    tree, ev = make("""
        root:
          retry:
            attempts: 5
            delay: 1.0
            backoff: 10.0
            max_delay: 2.5
            child: {probe: {tag: try, script: F}}
        """)
    r = tree.root
    assert [r.delay_after(n) for n in (1, 2, 3)] == [1.0, 2.5, 2.5]


def test_retry_never_restarts_in_the_failing_tick_and_runs_on_retry(make):
    tree, ev = make("""
        root:
          retry:
            attempts: 3
            child: {probe: {tag: try, script: F}}
            on_retry: {probe: {tag: fix, script: S}}
        """)
    assert tree.tick() is Status.RUNNING
    assert ev == ["try:start", "try:end"]
    tree.tick()
    assert ev == ["try:start", "try:end", "fix:start", "fix:end", "try:start", "try:end"]


def test_retry_succeeds_when_child_does(make):
    tree, ev = make("""
        root:
          retry: {attempts: 3, child: {probe: {tag: t, script: S}}}
        """)
    assert tree.tick() is Status.SUCCESS


def test_timeout_halts_child_and_writes_error(make, clock):
    tree, ev = make("""
        root:
          timeout:
            seconds: 1.0
            error_code: NAV_TIMEOUT
            child: {probe: {tag: slow, script: R}}
        """)
    status = tree.run(hz=10)
    assert status is Status.FAILURE
    assert clock.now() == pytest.approx(1.0)
    assert ev == ["slow:start", "slow:halt"]
    assert tree.error().code == "NAV_TIMEOUT"


def test_repeat_inverter_force(make):
    tree, ev = make("root:\n  repeat: {count: 3, child: {probe: {tag: r, script: S}}}\n")
    assert tick_n(tree, 2) is Status.RUNNING
    assert tree.tick() is Status.SUCCESS and ev.count("r:start") == 3
    for text, want in (("inverter: {child: success}", Status.FAILURE), ("inverter: {child: failure}", Status.SUCCESS),
                       ("force_success: {child: failure}", Status.SUCCESS),
                       ("force_failure: {child: success}", Status.FAILURE),
                       ("force_success: {child: running}", Status.RUNNING)):
        tree, _ = make("root:\n  " + text + "\n")
        assert tree.tick() is want, text


def test_one_shot_policies(make):
    tree, ev = make("root:\n  one_shot: {child: {probe: {tag: o, script: S}}}\n")
    assert tick_n(tree, 3) is Status.SUCCESS and ev.count("o:start") == 1
    tree, ev = make("root:\n  one_shot: {child: {probe: {tag: o, script: F}}}\n")
    tick_n(tree, 3)
    assert ev.count("o:start") == 3               # on_success: failures run again
    tree, ev = make("root:\n  one_shot: {policy: on_completion, child: {probe: {tag: o, script: F}}}\n")
    assert tick_n(tree, 3) is Status.FAILURE and ev.count("o:start") == 1


def test_guard_every_tick_halts_child(make):
    tree, ev = make("""
        root:
          guard:
            condition: "battery > 0.2 and not estop"
            child: {probe: {tag: work, script: R}}
        blackboard:
          battery: {type: float, default: 0.9}
          estop: {type: bool, default: false}
        """)
    tick_n(tree, 2)
    tree.blackboard.set("/battery", 0.1)
    assert tree.tick() is Status.FAILURE
    assert ev == ["work:start", "work:halt"]


def test_guard_on_start_and_when_false_success(make):
    tree, ev = make("""
        blackboard:
          go: bool          # written from outside the tree (this test)
        root:
          guard:
            condition: go
            check: on_start
            child: {probe: {tag: work, script: RRS}}
        """)
    assert tree.tick() is Status.FAILURE and ev == []
    tree.blackboard.set("/go", True)
    tree.tick()
    tree.blackboard.set("/go", False)             # not re-checked while running
    assert tick_n(tree, 2) is Status.SUCCESS
    tree, ev = make("blackboard: {go: bool}\nroot:\n  guard: {condition: go, when_false: success, child: failure}\n")
    assert tree.tick() is Status.SUCCESS


def test_guard_with_condition_node(make):
    tree, ev = make("""
        blackboard:
          ready: bool          # written from outside the tree (this test)
        root:
          guard:
            condition: {flag: {key: $bb.ready}}
            child: {probe: {tag: w, script: S}}
        """)
    assert tree.tick() is Status.FAILURE
    tree.blackboard.set("/ready", True)
    assert tree.tick() is Status.SUCCESS


def test_decorator_value_checks(check):
    assert "`attempts` must be at least 1" in check("root:\n  retry: {attempts: 0, child: success}\n")[0]
    assert "`backoff` must be at least 1" in check("root:\n  retry: {attempts: 2, backoff: 0.5, child: success}\n")[0]
    assert "`seconds` must be greater than 0" in check("root:\n  timeout: {seconds: 0, child: success}\n")[0]
    assert "`count` must be at least 1 (or -1)" in check("root:\n  repeat: {count: 0, child: success}\n")[0]
    errs = check("root:\n  guard: {condition: {probe: {tag: x}}, child: success}\n")
    assert "must be a condition" in errs[0]
