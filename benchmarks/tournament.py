"""HTN against the greedy baseline, head to head: wins, and games per hour on 1 and 2 workers.

A round robin of ``htn`` and ``baseline`` (``rll-bt tournament``): every
seed twice, each configuration once in each colour, whole lockstep games
(three robots a team, Algorithm 1 exploration, SETUP shortened to 10 s).
Played first on 2 workers (the local pool, ``--jobs 2``), which gives the
table; then ``--speed-seeds`` of those seeds again on 1 worker into a store
of their own, which gives the games per hour of one worker and checks that
the same games give the same rows.

    .venv/bin/python benchmarks/tournament.py [--seeds 20] [--speed-seeds 1] [--out DIR]
                                              [--profile rcll2016] [--production S]

The stores stay in ``--out``: run the same command again after a kill and
it plays only what is missing (the games-per-hour figures then count only
the games played in this run).

Aim: HTN wins at least 90 % of the games.
"""
from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

from games.tournament import run_tournament
from games.tournament.play import game_part
from rll_bt import rules

CONFIGS = ["htn", "baseline"]


def _rate(out: dict, wall: float) -> float | None:
    return out["played"] / wall * 3600.0 if out["played"] and wall > 0 else None


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--profile", default="rcll2016", choices=rules.PROFILES)
    ap.add_argument("--seeds", type=int, default=20, help="seeds 1..N (default 20)")
    ap.add_argument("--speed-seeds", type=int, default=1, help="seeds played again on 1 worker (default 1)")
    ap.add_argument("--production", type=float, help="PRODUCTION length in game s (default: the rules')")
    ap.add_argument("--out", type=Path, default=Path("benchmark-tournament"))
    args = ap.parse_args(argv)
    seeds = list(range(1, args.seeds + 1))
    game = {"profile": args.profile, "production": args.production}
    t0 = time.perf_counter()
    two = run_tournament(CONFIGS, seeds, args.out / "two-workers", jobs=2, progress=True, **game)
    wall2 = time.perf_counter() - t0
    t1 = time.perf_counter()
    one = run_tournament(CONFIGS, seeds[:args.speed_seeds], args.out / "one-worker", jobs=1, progress=True, **game)
    wall1 = time.perf_counter() - t1
    by_key = {r["key"]: r for r in two["rows"]}
    same = all(game_part(r) == game_part(by_key[r["key"]]) for r in one["rows"] if r["key"] in by_key)
    print(render(args, seeds, two, one, wall2, wall1, same))
    return 0 if not two["failed"] and not one["failed"] else 1


def render(args, seeds, two, one, wall2, wall1, same) -> str:
    rows = [r for r in two["rows"] if not r.get("error")]
    htn_wins = sum(r["winner"] == "htn" for r in rows)
    as_color = {c: [r for r in rows if r[c] == "htn"] for c in ("cyan", "magenta")}
    lines = [f"tournament htn vs baseline, {args.profile}, seeds {seeds[0]}..{seeds[-1]} in both colours, "
             f"3 robots a team; {len(rows)} of {two['planned']} games" +
             (f", {len(two['failed'])} failed" if two["failed"] else ""), "", two["table"], ""]
    share = htn_wins / len(rows) if rows else 0.0
    lines.append(f"HTN wins {htn_wins}/{len(rows)} games ({100 * share:.0f} %; aim >= 90 %): "
                 + ", ".join(f"{sum(r['winner'] == 'htn' for r in rs)}/{len(rs)} as {c}"
                             for c, rs in as_color.items()))
    margin = [r["points"]["cyan" if r["cyan"] == "htn" else "magenta"]
              - r["points"]["magenta" if r["cyan"] == "htn" else "cyan"] for r in rows]
    if margin:
        lines.append(f"HTN's margin per game: mean {sum(margin) / len(margin):.1f}, min {min(margin)}, "
                     f"max {max(margin)} points")
    lines.append(f"inter-team collisions: {sum(r['collisions_between_teams'] for r in rows)} in {len(rows)} games")
    known = [r for r in rows if r.get("collisions_within_teams") is not None]
    if known:
        own = {cfg: sum(r["collisions_within_teams"][c] for r in known for c in ("cyan", "magenta") if r[c] == cfg)
               for cfg in CONFIGS}
        hit = {k: sum(r["collisions_with"][k] for r in known) for k in ("station", "wall")}
        lines.append(f"collisions within a team: {', '.join(f'{k} {v}' for k, v in own.items())}; "
                     f"with stations {hit['station']}, walls {hit['wall']} (in {len(known)} games)")
    lines.append("")
    for workers, out, wall in ((2, two, wall2), (1, one, wall1)):
        rate = _rate(out, wall)
        lines.append(f"{workers} worker{'s' if workers > 1 else ''}: {out['played']} games played in {wall:.0f} s "
                     f"wall = " + (f"{rate:.1f} games/hour" if rate else "- (nothing played in this run)"))
    lines.append(f"the {len(one['rows'])} games replayed on 1 worker gave the same rows: {'yes' if same else 'NO'}")
    return "\n".join(lines)


if __name__ == "__main__":
    sys.exit(main())
