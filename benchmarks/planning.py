"""Planning and repair time of the team server's HTN planner, printed as a table.

    .venv/bin/python benchmarks/planning.py [--runs 200] [--seed 1]

For each rules profile, over ``--runs`` random games (orders drawn from the
profile's order shapes, random ring costs, 3 robots):

- ``decompose all``: the HTN networks of every active order;
- ``plan round``: one whole planning round of the server (every candidate
  decomposed, then the anytime choice, whose budget is 40 ms / 60 simulations);
- ``repair``: re-planning one product after a failure, from a held workpiece.

The aim is 50 ms or less (median) for a planning round.  If the ``gtpyhop``
package is installed, the same C3 product is also planned with it (totally
ordered, one deepcopy of the state per action) for comparison; see
docs/planning.md.
"""
from __future__ import annotations

import argparse
import contextlib
import io
import random
import statistics
import sys
import time

from rll_bt import rules
from rll_bt.clock import WallClock
from teamserver.knowledge import model as M
from teamserver.planning.domain import Progress
from teamserver.planning.estimate import SimRobot
from teamserver.planning.planner import ProductionPlanner, World

CAPS = {"C-CS1": "CAP_GREY", "C-CS2": "CAP_BLACK"}


def random_world(profile, rng: random.Random, now: float = 0.0) -> World:
    rs, costs = profile.ring_setup(rng)
    rs_colors = {f"C-{k}": v for k, v in rs.items()}
    zones = rng.sample(profile.machine_zones("CYAN"), len(profile.machine_types))
    positions = {f"C-{k}": profile.zone_centre(z) for k, z in zip(profile.machine_types, zones)}
    orders = []
    for i, shape in enumerate(profile.orders, start=1):
        if shape.overtime:
            continue
        c = rng.choice(shape.complexities)
        begin = 0 if shape.standing else rng.randrange(0, 600)
        end = profile.phases.production if shape.standing else begin + rng.randrange(150, 400)
        orders.append(M.Order(i, c, rng.choice(rules.BASE_COLORS),
                              tuple(rng.choice(rules.RING_COLORS) for _ in range(c)),
                              rng.choice(rules.CAP_COLORS), shape.quantity, 0, begin, end,
                              rng.randint(1, 3), shape.competitive))
    robots = [SimRobot(str(i), (4.5, 0.5), now) for i in (1, 2, 3)]
    return World(orders, robots, positions, rs_colors, costs, CAPS, now,
                 profile.phases.production, max_products=3)


def timed(fn) -> float:
    t0 = time.perf_counter()
    fn()
    return (time.perf_counter() - t0) * 1000.0


def bench_profile(name: str, runs: int, seed: int) -> list[tuple]:
    profile = rules.profile(name)
    rng = random.Random(seed)
    planner = ProductionPlanner(profile, "C", clock=WallClock())
    dec, rnd, rep, evals, pts = [], [], [], [], []
    for _ in range(runs):
        w = random_world(profile, rng)

        def decompose_all():
            for o in w.orders:
                planner.decompose(planner.context(w, o))

        dec.append(timed(decompose_all))
        box = {}
        rnd.append(timed(lambda: box.setdefault("c", planner.choose(w))))
        evals.append(box["c"].evaluations)
        pts.append(box["c"].points)
        o = max(w.orders, key=lambda o: o.complexity)
        held = Progress(base=o.base, rings=o.rings[:1], location="robot:2",
                        slide_credit={}, cap_ready=None)
        rep.append(timed(lambda: planner.decompose(planner.context(w, o, held))))
    n_orders = len(random_world(profile, random.Random(0)).orders)
    return [
        (name, f"decompose all ({n_orders} orders)", *stats(dec)),
        (name, "plan round (decompose + anytime choice)", *stats(rnd)),
        (name, "repair one product", *stats(rep)),
        (name, f"  simulations per round: median {statistics.median(evals):.0f}; "
               f"planned points median {statistics.median(pts):.0f}", "", "", ""),
    ]


def stats(ms: list[float]) -> tuple[str, str, str]:
    ms = sorted(ms)
    return (f"{statistics.median(ms):.2f}", f"{ms[int(0.9 * (len(ms) - 1))]:.2f}",
            f"{ms[-1]:.2f}")


def bench_gtpyhop(runs: int) -> list[tuple]:
    """The C3 product of the domain as a GTPyhop problem (if gtpyhop is installed)."""
    try:
        with contextlib.redirect_stdout(io.StringIO()):
            import gtpyhop
    except ImportError:
        return [("gtpyhop", "not installed (pip install -e '.[bench]' to compare)", "", "", "")]
    with contextlib.redirect_stdout(io.StringIO()):
        gtpyhop.Domain("rcll_bench")
        gtpyhop.set_verbose_level(0) if hasattr(gtpyhop, "set_verbose_level") else None

    def a_get(s, m):
        if s.holding is None:
            s.holding = m
            return s

    def a_put(s, m):
        if s.holding is not None:
            s.holding = None
            s.placed.append(m)
            return s

    def a_mount(s, m, c):
        if s.holding is not None:
            s.product.append(c)
            return s

    gtpyhop.declare_actions(a_get, a_put, a_mount)

    def m_ring(s, rs, color, cost):
        return [t for _ in range(cost) for t in (("a_get", "BS"), ("a_put", rs))] + [
            ("a_get", "BS"), ("a_mount", rs, color), ("a_put", rs)]

    def m_product(s):
        todo = []
        for color, rs, cost in s.rings:
            todo.append(("ring", rs, color, cost))
        return todo + [("a_get", "CS"), ("a_put", "CS"), ("a_get", "CS"), ("a_mount", "CS", "cap"),
                       ("a_get", "CS"), ("a_put", "DS")]

    gtpyhop.declare_task_methods("ring", m_ring)
    gtpyhop.declare_task_methods("product", m_product)
    # the state a team server would plan in: the knowledge base's records
    kb_like = {f"obs{i}": {"machine": "C-RS1", "value": i, "conf": 0.5} for i in range(300)}
    out = []
    for label, extra in (("small state", {}), ("state with 300 observation records", kb_like)):
        times = []
        for _ in range(runs):
            s = gtpyhop.State("s")
            s.holding, s.placed, s.product = None, [], []
            s.rings = [("RING_BLUE", "RS1", 2), ("RING_ORANGE", "RS2", 1), ("RING_GREEN", "RS1", 0)]
            s.kb = extra
            with contextlib.redirect_stdout(io.StringIO()):
                times.append(timed(lambda: gtpyhop.find_plan(s, [("product",)])))
        out.append(("gtpyhop", f"one C3 product, {label}", *stats(times)))
    return out


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--runs", type=int, default=200)
    ap.add_argument("--seed", type=int, default=1)
    args = ap.parse_args(argv)
    rows = []
    for name in rules.PROFILES:
        print(f"benchmarking {name} ({args.runs} games) ...", file=sys.stderr)
        rows += bench_profile(name, args.runs, args.seed)
    # our engine on the same C3 product, for the gtpyhop comparison
    p = rules.profile("rcll2016")
    planner = ProductionPlanner(p, "C", clock=WallClock())
    w = random_world(p, random.Random(args.seed))
    o = M.Order(99, 3, "BASE_RED", ("RING_BLUE", "RING_ORANGE", "RING_GREEN"), "CAP_GREY", 1, 0,
                0, 900, 1)
    w.rs_colors = {"C-RS1": ("RING_BLUE", "RING_GREEN"), "C-RS2": ("RING_ORANGE", "RING_YELLOW")}
    w.ring_costs = {"RING_BLUE": 2, "RING_ORANGE": 1, "RING_GREEN": 0, "RING_YELLOW": 0}
    ours = [timed(lambda: planner.decompose(planner.context(w, o))) for _ in range(args.runs)]
    rows.append(("own engine", "one C3 product (partially ordered)", *stats(ours)))
    rows += bench_gtpyhop(args.runs)
    head = ("profile", "what", "median ms", "p90 ms", "max ms")
    widths = [max(len(str(r[i])) for r in rows + [head]) for i in range(5)]
    print("  ".join(h.ljust(w) for h, w in zip(head, widths)))
    print("  ".join("-" * w for w in widths))
    for r in rows:
        print("  ".join(str(c).ljust(w) for c, w in zip(r, widths)).rstrip())
    return 0


if __name__ == "__main__":
    sys.exit(main())
