"""Exploration strategies side by side in whole simulated games.

For every seed and strategy (Algorithm 1 of the paper with our extensions,
Algorithm 1 exactly as printed, random, nearest, and the oracle that knows
where the stations stand) a lockstep game with three robots plays its
exploration (SETUP shortened to 1 s) and stops as soon as every exploration
point is scored, or when the exploration time is over.  Measured per game:
the exploration points, and the time until every own station was correctly
known: the game seconds until the refbox had accepted a correct report of
every property it scores for every own station (2016: zone and type, the
type read from the light code; 2025: zone and rotation), i.e. every
exploration point was scored (a game that never scores them all counts the
whole exploration window).  "sure" counts the games in which the team
server's own belief reached its reporting confidence for every station and
value before the game stopped (it may report earlier, near the deadline or
when a value is clearly ahead).

    .venv/bin/python benchmarks/exploration.py [--profile rcll2016|rcll2025] [--seeds 30]
                                               [--strategies algorithm1,algorithm1-paper,random,nearest,oracle]
                                               [--jobs 2] [--per-seed] [--json FILE]

Aim: full points in at least 95 % of seeds and a median time within 1.3x
of the oracle's.
"""
from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

from games.batch import fmt, median, run_batch
from games.options import GameOptions, published
from rll_bt import rules


def main(argv=None) -> int:
    strategies_known = published("strategy", "htn")       # the team server's own list
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--profile", default="rcll2016", choices=rules.PROFILES)
    ap.add_argument("--seeds", type=int, default=30, help="seeds 1..N (default 30)")
    ap.add_argument("--first-seed", type=int, default=1)
    ap.add_argument("--strategies", default=",".join(strategies_known))
    ap.add_argument("--jobs", type=int, default=2, help="games in parallel (default 2)")
    ap.add_argument("--perception", default="oracle", choices=("oracle", "rendered"),
                    help="oracle (default): the simulator hands over tags and lights in view; rendered: the "
                         "detectors read every robot's camera frames")
    ap.add_argument("--per-seed", action="store_true", help="also print every game")
    ap.add_argument("--json", type=Path, help="write every game's numbers here")
    args = ap.parse_args(argv)
    strategies = [s for s in args.strategies.split(",") if s]
    bad = set(strategies) - set(strategies_known)
    if bad:
        ap.error(f"unknown strategy {', '.join(sorted(bad))} (known: {', '.join(strategies_known)})")
    seeds = list(range(args.first_seed, args.first_seed + args.seeds))
    games = [GameOptions(profile=args.profile, seed=s, strategy=st, until="exploration", setup=1.0,
                         perception=args.perception)
             for st in strategies for s in seeds]
    t0 = time.perf_counter()

    def done(i, row):
        g = games[i]
        what = row.get("error") or (f"{row['exploration']['points']} pts, all after "
                                    f"{fmt(row['exploration']['all_points_after'])} s")
        print(f"  [{time.perf_counter() - t0:6.0f} s] {g.strategy:16} seed {g.seed:3d}: {what}",
              file=sys.stderr, flush=True)

    rows = run_batch(games, jobs=args.jobs, stop="explored", done=done)
    wall = time.perf_counter() - t0
    if args.json:
        args.json.write_text(json.dumps(rows, indent=1, default=str))
    print(render(args.profile, strategies, seeds, games, rows, wall, args.per_seed, args.perception))
    return 0 if all("error" not in r for r in rows) else 1


def known_after(game, row) -> float:
    """Game seconds until every exploration point was scored (the window when never)."""
    t = row["exploration"]["all_points_after"]
    return t if t is not None else game.exploration_window()


def render(profile, strategies, seeds, games, rows, wall, per_seed=False, perception="oracle") -> str:
    by = {st: [(g, r) for g, r in zip(games, rows) if g.strategy == st and "error" not in r] for st in strategies}
    errors = {st: sum(1 for g, r in zip(games, rows) if g.strategy == st and "error" in r) for st in strategies}
    oracle = median(known_after(g, r) for g, r in by.get("oracle", []))
    lines = [f"exploration, {profile}, {len(seeds)} seeds ({seeds[0]}..{seeds[-1]}), 3 robots, "
             f"{perception} perception; {wall:.0f} s wall",
             "",
             f"{'strategy':16} {'full points':>12} {'median pts':>11} {'median time s':>14} {'vs oracle':>10} "
             f"{'mean time s':>12} {'sure':>7} {'wrong':>7} {'errors':>7}",
             f"{'-' * 16} {'-' * 12} {'-' * 11} {'-' * 14} {'-' * 10} {'-' * 12} {'-' * 7} {'-' * 7} {'-' * 7}"]
    for st in strategies:
        ok = by[st]
        full = sum(1 for _, r in ok if r["exploration"]["points"] >= r["exploration"]["max_points"])
        sure = sum(1 for _, r in ok if r["exploration"]["sure_all_after"] is not None)
        times = [known_after(g, r) for g, r in ok]
        med = median(times)
        ratio = med / oracle if med is not None and oracle else None
        share = f"{full}/{len(ok)} ({100 * full / len(ok):.0f}%)" if ok else "-"
        mean = sum(times) / len(times) if times else None
        lines.append(f"{st:16} {share:>12} {fmt(median(r['exploration']['points'] for _, r in ok), '.0f'):>11} "
                     f"{fmt(med):>14} {fmt(ratio, '.2f') + 'x' if ratio else '-':>10} {fmt(mean):>12} "
                     f"{sure:>3}/{len(ok):<3} {sum(r['exploration'].get('wrong', 0) for _, r in ok):>7} "
                     f"{errors[st]:>7}")
    if per_seed:
        lines += ["", f"{'strategy':16} {'seed':>4} {'points':>6} {'all points s':>12} {'sure s':>7} {'wrong':>5} "
                      f"{'wall s':>7}"]
        for g, r in zip(games, rows):
            if "error" in r:
                lines.append(f"{g.strategy:16} {g.seed:4d} error: {r['error']}")
            else:
                ex = r["exploration"]
                lines.append(f"{g.strategy:16} {g.seed:4d} {ex['points']:6d} {fmt(ex['all_points_after']):>12} "
                             f"{fmt(ex['sure_all_after']):>7} {ex.get('wrong', 0):>5} {fmt(r['wall_time'], '.0f'):>7}")
    return "\n".join(lines)


if __name__ == "__main__":
    sys.exit(main())
