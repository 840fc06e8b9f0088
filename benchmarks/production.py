"""Production points per game: the HTN team server against a greedy baseline.

For every seed two whole lockstep games are played (three robots, oracle
perception, Algorithm 1 exploration, SETUP shortened to 10 s): one with the
team server's HTN planning (several products at once, orders chosen by
simulating the plan), one with the greedy baseline (one order at a time,
the plannable one with the earliest deadline; ``rll-bt sim --baseline``).
Measured per game: production points, orders delivered, total score, our
stations that went BROKEN (by the refbox's cause) and the referee calls the
refbox leaves to a human referee (reported, not scored).  The simulated
refbox plays the real refbox's rules (docs/refbox.md).

    .venv/bin/python benchmarks/production.py [--profile rcll2016|rcll2025] [--seeds 20]
                                              [--jobs 2] [--per-seed] [--json FILE]
                                              [--variants htn,baseline] [--jsonl FILE]
    .venv/bin/python benchmarks/production.py --profile P --from-jsonl FILE [FILE ...]

``--jsonl`` appends every game's numbers to FILE as the game ends (a long run
cut short keeps what it played); ``--from-jsonl`` prints the tables from such
files instead of playing (the seeds and variants found there).

Aims (issue 17): a mean of at least 300 production points, no game under 150,
at least 1.5x the baseline, and no station of ours BROKEN in any game.
"""
from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

from games.batch import fmt, mean, median, run_batch
from games.options import GameOptions
from rll_bt import rules

VARIANTS = {"htn": False, "baseline": True}
#: how the simulated refbox judges a delivery (backends/sim/refbox/orders2016.py, orders2025.py)
JUDGEMENTS = ("in-time", "late", "too-late", "too-soon", "wrong-gate", "wrong-product",
              "too-many", "no-order")


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--profile", default="rcll2016", choices=rules.PROFILES)
    ap.add_argument("--seeds", type=int, default=20, help="seeds 1..N (default 20)")
    ap.add_argument("--first-seed", type=int, default=1)
    ap.add_argument("--production", type=float, help="PRODUCTION length in game s (default: the rules')")
    ap.add_argument("--jobs", type=int, default=2, help="games in parallel (default 2)")
    ap.add_argument("--perception", default="oracle", choices=("oracle", "rendered"),
                    help="oracle (default): the simulator hands over tags and lights in view; rendered: the "
                         "detectors read every robot's camera frames")
    ap.add_argument("--per-seed", action="store_true", help="also print every game")
    ap.add_argument("--json", type=Path, help="write every game's numbers here")
    ap.add_argument("--variants", default="htn,baseline",
                    help="team servers to play, comma separated (default htn,baseline)")
    ap.add_argument("--jsonl", type=Path, help="append every game's numbers here as it ends")
    ap.add_argument("--from-jsonl", type=Path, nargs="+", metavar="FILE",
                    help="print the tables from these --jsonl files instead of playing")
    args = ap.parse_args(argv)
    names = [v.strip() for v in args.variants.split(",") if v.strip()]
    if not names or any(v not in VARIANTS for v in names):
        ap.error(f"--variants: choose from {', '.join(VARIANTS)}")
    if args.from_jsonl:
        return from_jsonl(args.profile, args.from_jsonl, args.per_seed)
    seeds = list(range(args.first_seed, args.first_seed + args.seeds))
    games = [GameOptions(profile=args.profile, seed=s, baseline=VARIANTS[v], production=args.production,
                         perception=args.perception)
             for s in seeds for v in names]
    t0 = time.perf_counter()

    def done(i, row):
        g = games[i]
        if args.jsonl:
            with args.jsonl.open("a", encoding="utf-8") as f:
                f.write(json.dumps({"profile": g.profile, "seed": g.seed, "baseline": g.baseline,
                                    "row": row}, default=str) + "\n")
        what = row.get("error") or (f"{row['points']['production']} production pts, "
                                    f"{row['orders_delivered']} orders, "
                                    f"{broken(row)} stations broken")
        print(f"  [{time.perf_counter() - t0:6.0f} s] {'baseline' if g.baseline else 'htn':8} seed {g.seed:3d}: "
              f"{what}", file=sys.stderr, flush=True)

    rows = run_batch(games, jobs=args.jobs, done=done)
    wall = time.perf_counter() - t0
    if args.json:
        args.json.write_text(json.dumps(rows, indent=1, default=str))
    print(render(args.profile, seeds, games, rows, wall, args.per_seed, args.perception))
    return 0 if all("error" not in r for r in rows) else 1


def from_jsonl(profile: str, files, per_seed: bool) -> int:
    """The tables of the games stored by ``--jsonl`` (``profile``'s; a seed and variant
    played twice: the last)."""
    got: dict[tuple[int, bool], dict] = {}
    for path in files:
        try:
            lines = Path(path).read_text(encoding="utf-8").splitlines()
        except OSError as exc:
            print(f"production.py: cannot read {path}: {exc}", file=sys.stderr)
            return 2
        for n, line in enumerate(lines, 1):
            try:
                item = json.loads(line)
                if item["profile"] == profile:
                    got[(int(item["seed"]), bool(item["baseline"]))] = item["row"]
            except (ValueError, KeyError, TypeError):
                print(f"production.py: {path}:{n}: not a game's line, skipped", file=sys.stderr)
    if not got:
        print(f"production.py: no {profile} games in {', '.join(map(str, files))}", file=sys.stderr)
        return 1
    keys = sorted(got)
    seeds = sorted({s for s, _ in keys})
    games = [GameOptions(profile=profile, seed=s, baseline=b) for s, b in keys]
    print(render(profile, seeds, games, [got[k] for k in keys], float("nan"), per_seed))
    return 0


def broken(row: dict) -> int:
    """Our stations that went BROKEN in the game."""
    return int(row.get("stations_broken", {}).get("total", 0))


def calls(row: dict) -> int:
    return sum(c.get("count", 0) for c in row.get("referee", {}).get("calls", {}).values())


def render(profile, seeds, games, rows, wall, per_seed=False, perception="oracle") -> str:
    by = {name: [r for g, r in zip(games, rows) if g.baseline == base and "error" not in r]
          for name, base in VARIANTS.items()}
    errors = sum(1 for r in rows if "error" in r)
    wall_text = f"; {wall:.0f} s wall" if wall == wall else ""
    lines = [f"production, {profile}, {len(seeds)} seeds ({seeds[0]}..{seeds[-1]}), 3 robots, "
             f"{perception} perception{wall_text}" + (f"; {errors} games failed" if errors else ""),
             "",
             f"{'team server':12} {'games':>5} {'mean prod pts':>14} {'median':>7} {'min':>5} {'max':>5} "
             f"{'>=150 pts':>10} {'orders/game':>12} {'mean score':>11} {'broken':>7} {'referee':>8}",
             f"{'-' * 12} {'-' * 5} {'-' * 14} {'-' * 7} {'-' * 5} {'-' * 5} {'-' * 10} {'-' * 12} {'-' * 11} "
             f"{'-' * 7} {'-' * 8}"]
    means = {}
    for name, rs in by.items():
        pts = [r["points"]["production"] for r in rs]
        means[name] = mean(pts)
        bar = sum(1 for p in pts if p >= 150)
        lines.append(f"{name:12} {len(rs):5d} {fmt(mean(pts)):>14} {fmt(median(pts), '.0f'):>7} "
                     f"{fmt(min(pts) if pts else None, 'd'):>5} {fmt(max(pts) if pts else None, 'd'):>5} "
                     f"{bar:>4}/{len(rs):<5} {fmt(mean(r['orders_delivered'] for r in rs), '.2f'):>12} "
                     f"{fmt(mean(r['points']['total'] for r in rs)):>11} {sum(broken(r) for r in rs):>7d} "
                     f"{sum(calls(r) for r in rs):>8d}")
    seen = {d.get("how") for rs in by.values() for r in rs for d in r.get("deliveries", ())}
    hows = [h for h in JUDGEMENTS if h in seen] + sorted(h for h in seen - set(JUDGEMENTS) if h)
    lines += ["", "deliveries per game, by the refbox's judgement:",
              f"{'team server':12} " + " ".join(f"{h:>13}" for h in hows)]
    for name, rs in by.items():
        counts = [sum(1 for r in rs for d in r.get("deliveries", ()) if d.get("how") == h)
                  for h in hows]
        lines.append(f"{name:12} " + " ".join(f"{fmt(c / len(rs) if rs else None, '.2f'):>13}"
                                               for c in counts))
    causes: dict[str, dict[str, int]] = {}
    refs: dict[str, dict[str, int]] = {}
    for name, rs in by.items():
        for r in rs:
            for k, v in r.get("stations_broken", {}).get("by_cause", {}).items():
                causes.setdefault(name, {})[k] = causes.get(name, {}).get(k, 0) + v
            for k, v in r.get("referee", {}).get("calls", {}).items():
                refs.setdefault(name, {})[k] = refs.get(name, {}).get(k, 0) + v.get("count", 0)
    lines += ["", "our stations BROKEN (all games, by cause) and referee calls (reported, not scored):"]
    for name in by:
        lines.append(f"{name:12} broken: " + (", ".join(f"{k} {v}" for k, v in sorted(
            causes.get(name, {}).items())) or "none") + "; referee: " + (", ".join(
            f"{k} {v}" for k, v in sorted(refs.get(name, {}).items())) or "none"))
    if means.get("baseline") and means.get("htn") is not None:
        lines += ["", f"HTN / baseline (mean production points): {means['htn'] / means['baseline']:.2f}x"]
    elif means.get("htn") is not None and means.get("baseline") is not None:
        lines += ["", "HTN / baseline: the baseline scored no production points"]
    if per_seed:
        lines += ["", f"{'seed':>4} {'htn pts':>8} {'orders':>7} {'broken':>7} {'baseline pts':>13} "
                      f"{'orders':>7} {'broken':>7}"]
        table = {}
        for g, r in zip(games, rows):
            table.setdefault(g.seed, {})["baseline" if g.baseline else "htn"] = r
        for seed in seeds:
            cells = []
            for name in VARIANTS:
                r = table.get(seed, {}).get(name, {})
                if not r:
                    cells.append(f"{'-':>8} {'':>7} {'':>7}")           # not played
                elif "error" in r:
                    cells.append(f"{'error':>8} {'':>7} {'':>7}")
                else:
                    cells.append(f"{r['points']['production']:8d} {r['orders_delivered']:7d} "
                                 f"{broken(r):7d}")
            lines.append(f"{seed:4d} {cells[0]} {cells[1].rjust(29)}")
    return "\n".join(lines)


if __name__ == "__main__":
    sys.exit(main())
