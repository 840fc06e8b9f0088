"""Tick time of a tree loaded from YAML against the same tree built by hand
in py_trees.

The tree (33 behaviours) is a reactive selector over an emergency branch,
a guarded work branch with a parallel, decorators and blackboard checks,
and a running leaf, so every tick walks most of it.  The hand-built twin
uses py_trees' own behaviours (CheckBlackboardVariableValue on the global
blackboard, Success, Running, Inverter, Retry, FailureIsSuccess, Parallel)
and is ticked through ``py_trees.trees.BehaviourTree`` and, as a stricter
baseline, by its root's ``tick_once`` alone (no tree visitors or handlers);
the YAML tree is ticked through ``LoadedTree.tick``.  Both trees use their
own blackboards (py_trees' access-checked one, rll_bt's typed one), as a user
of either would.  Aim: the YAML tree within 10 % of the hand-built one.

    .venv/bin/python benchmarks/tick_overhead.py [--ticks 20000] [--repeats 5]
"""
from __future__ import annotations

import argparse
import operator
import time

import py_trees
from py_trees.common import ComparisonExpression, ParallelPolicy

from rll_bt.clock import SimClock
from rll_bt.tree import RunContext, default_registry, load_tree
from rll_bt.tree.ticklog import TickLogger

TREE = """
name: bench
blackboard:
  estop: {type: bool, default: false}
  battery: {type: float, default: 0.9}
  bumper: {type: bool, default: false}
  mode: {type: str, default: work}
root:
  reactive_selector:
    name: root
    children:
      - reactive_sequence:
          name: emergency
          children:
            - check_blackboard: {condition: "estop == true"}
            - running
      - reactive_sequence:
          name: charge
          children:
            - check_blackboard: {condition: "battery < 0.2"}
            - running
      - reactive_sequence:
          name: work
          children:
            - check_blackboard: {condition: "battery > 0.2"}
            - inverter: {child: {check_blackboard: {condition: "bumper == true"}}}
            - check_blackboard: {condition: "mode == 'work'"}
            - parallel:
                policy: all
                synchronise: false
                children:
                  - success
                  - force_success: {child: failure}
                  - retry: {attempts: 3, child: success}
                  - reactive_sequence: [success, success, success]
            - reactive_selector:
                - check_blackboard: {condition: "estop == true"}
                - check_blackboard: {condition: "bumper == true"}
                - success
            - reactive_sequence:
                - success
                - inverter: {child: failure}
                - check_blackboard: {condition: "battery > 0.5"}
            - running
      - running
"""


def by_hand() -> py_trees.behaviour.Behaviour:
    """The same tree with py_trees' own classes."""
    bb = py_trees.blackboard.Blackboard
    bb.set("/estop", False)
    bb.set("/battery", 0.9)
    bb.set("/bumper", False)
    bb.set("/mode", "work")
    S, Sel = py_trees.composites.Sequence, py_trees.composites.Selector
    ok, fail, run = py_trees.behaviours.Success, py_trees.behaviours.Failure, py_trees.behaviours.Running

    def check(name, key, value, op):
        return py_trees.behaviours.CheckBlackboardVariableValue(name, check=ComparisonExpression(key, value, op))

    return Sel("root", memory=False, children=[
        S("emergency", memory=False, children=[check("estop", "estop", True, operator.eq), run("running")]),
        S("charge", memory=False, children=[check("battery low", "battery", 0.2, operator.lt), run("running")]),
        S("work", memory=False, children=[
            check("battery ok", "battery", 0.2, operator.gt),
            py_trees.decorators.Inverter("inverter", check("bumper", "bumper", True, operator.eq)),
            check("mode", "mode", "work", operator.eq),
            py_trees.composites.Parallel("parallel", policy=ParallelPolicy.SuccessOnAll(synchronise=False), children=[
                ok("success"),
                py_trees.decorators.FailureIsSuccess("force_success", fail("failure")),
                py_trees.decorators.Retry("retry", ok("success"), num_failures=3),
                S("reactive_sequence", memory=False, children=[ok("a"), ok("b"), ok("c")]),
            ]),
            Sel("reactive_selector", memory=False, children=[
                check("estop", "estop", True, operator.eq), check("bumper", "bumper", True, operator.eq),
                ok("success")]),
            S("reactive_sequence", memory=False, children=[
                ok("success"), py_trees.decorators.Inverter("inverter", fail("failure")),
                check("battery", "battery", 0.5, operator.gt)]),
            run("running"),
        ]),
        run("running"),
    ])


def count(root) -> int:
    return sum(1 for _ in root.iterate())


def time_ticks(tick, ticks: int, repeats: int) -> float:
    """Best mean seconds per tick over ``repeats`` runs of ``ticks`` ticks."""
    for _ in range(min(1000, ticks)):
        tick()
    best = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        for _ in range(ticks):
            tick()
        best.append((time.perf_counter() - t0) / ticks)
    return min(best)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--ticks", type=int, default=20000)
    ap.add_argument("--repeats", type=int, default=5)
    args = ap.parse_args()

    import tempfile
    from pathlib import Path
    with tempfile.TemporaryDirectory() as d:
        path = Path(d) / "bench.yaml"
        path.write_text(TREE)
        default_registry()          # node types and plug-ins, loaded once per process
        t0 = time.perf_counter()
        yaml_tree = load_tree(path, ctx=RunContext(clock=SimClock()))
        load_ms = (time.perf_counter() - t0) * 1e3
        logged_tree = load_tree(path, ctx=RunContext(clock=SimClock()))
    hand = py_trees.trees.BehaviourTree(by_hand())
    hand.setup()
    yaml_tree.setup()
    assert count(hand.root) == count(yaml_tree.root), (count(hand.root), count(yaml_tree.root))
    hand.tick()
    yaml_tree.tick()
    assert hand.root.status == yaml_tree.status == py_trees.common.Status.RUNNING

    t_hand = time_ticks(hand.tick, args.ticks, args.repeats)
    t_bare = time_ticks(hand.root.tick_once, args.ticks, args.repeats)
    t_yaml = time_ticks(yaml_tree.tick, args.ticks, args.repeats)
    sink = open("/dev/null", "w")  # noqa: SIM115
    logger = TickLogger(logged_tree, sink)
    t_logged = time_ticks(logged_tree.tick, max(1, args.ticks // 4), args.repeats)
    logger.close()
    sink.close()

    rows = [("py_trees, built by hand (BehaviourTree.tick)", t_hand),
            ("py_trees, built by hand (root.tick_once)", t_bare),
            ("rll_bt, loaded from YAML (LoadedTree.tick)", t_yaml),
            ("rll_bt, from YAML, with JSON-lines tick log", t_logged)]
    print(f"tree: {count(hand.root)} behaviours, {args.ticks} ticks x {args.repeats} repeats (best mean); "
          f"YAML load {load_ms:.1f} ms")
    print(f"{'variant':<48} {'us/tick':>9} {'ratio':>7}")
    for name, t in rows:
        print(f"{name:<48} {t * 1e6:9.1f} {t / t_hand:7.2f}")
    verdict = "within" if t_yaml <= 1.10 * t_hand else "NOT within"
    print(f"YAML/hand ratio {t_yaml / t_hand:.3f}: {verdict} the 10 % aim")
    bare = "within" if t_yaml <= 1.10 * t_bare else "NOT within"
    print(f"YAML/bare root ratio {t_yaml / t_bare:.3f}: {bare} 10 % of ticking the hand-built root alone "
          f"(no tree visitors or pre/post-tick handlers)")


if __name__ == "__main__":
    main()
