"""Memory of a whole process-mode game, sampled over time.

One ``rll-bt sim --processes`` game (the refbox, the team server and every
agent in processes of their own, the world in this one) is played to its
end; every ``--period`` seconds of game time the resident set size (VmRSS,
``/proc/PID/status``) of each process is sampled.  Printed: the table of
samples (MB per process, per minute of game time) and, per process, the
growth from the first minute to the end.  With ``--net-loss`` and
``--net-delay`` the robots' team-server links are faulted as with
``rll-bt sim --net-*`` (queues under repeated deliveries).

    .venv/bin/python benchmarks/memory_game.py [--profile rcll2016] [--seed 1] [--period 10]
                                               [--net-loss 0.2 --net-delay 2.0] [--json FILE]

Aim: flat after the first minute (each process within 10 % of its size at
60 s, or 10 MB).
"""
from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
from pathlib import Path

from games.options import GameOptions
from games.processes import ProcessGame
from rll_bt.comm.faults import NetFaults


def rss_mb(pid: int) -> float | None:
    try:
        for line in Path(f"/proc/{pid}/status").read_text().splitlines():
            if line.startswith("VmRSS:"):
                return int(line.split()[1]) / 1024.0
    except OSError:
        return None
    return None


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--profile", default="rcll2016")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--period", type=float, default=10.0, help="s of game time between samples (default 10)")
    ap.add_argument("--net-loss", type=float, default=0.0)
    ap.add_argument("--net-delay", type=float, default=0.0)
    ap.add_argument("--json", type=Path, help="write the samples here")
    args = ap.parse_args(argv)
    commit = subprocess.run(["git", "rev-parse", "--short", "HEAD"], capture_output=True, text=True,
                            cwd=Path(__file__).parent).stdout.strip()
    net = NetFaults(loss=args.net_loss, delay=args.net_delay, jitter=0.1 * args.net_delay)
    with tempfile.TemporaryDirectory(prefix="rll-bt-memory-") as tmp:
        opts = GameOptions(profile=args.profile, seed=args.seed, processes=True, out=Path(tmp), net=net)
        game = ProcessGame(opts, connect_timeout=300.0)
        samples: list[dict] = []
        next_t = [0.0]

        def sample(g) -> bool:
            t = g.clock.now() - g._t0
            if t >= next_t[0]:
                next_t[0] = t + args.period
                row = {"t": round(t, 1), "world": rss_mb(os.getpid())}
                for name, p in g.procs.items():
                    row[name] = rss_mb(p.pid)
                samples.append(row)
                print(f"  {row['t']:7.1f} s  " + "  ".join(f"{k} {v:.0f}" for k, v in row.items()
                                                          if k != "t" and v is not None),
                      file=sys.stderr, flush=True)
            return g.finished()
        try:
            limit = opts.expected_duration() + opts.rules.phases.overtime + 60.0
            game.run_until(sample, limit)
            result = game.result(game.finished())
        finally:
            game.close()
    if args.json:
        args.json.write_text(json.dumps({"commit": commit, "samples": samples}, indent=1))
    print(render(samples, args, commit, result.status.points.get("CYAN", 0)))
    return 0


def render(samples: list[dict], args, commit: str, points: int) -> str:
    names = [k for k in samples[0] if k != "t"] if samples else []
    lines = [f"memory of a process-mode game: {args.profile} seed {args.seed}, net loss {args.net_loss:g} "
             f"delay {args.net_delay:g} s; {points} points; commit {commit}", "",
             f"{'game s':>7} " + " ".join(f"{n:>10}" for n in names) + "   (RSS, MB)"]
    shown = [s for s in samples if int(s["t"]) % 60 < args.period] or samples
    for s in shown:
        lines.append(f"{s['t']:7.0f} " + " ".join(f"{(s.get(n) or 0):10.0f}" for n in names))
    lines += ["", f"{'process':10} {'at 60 s':>8} {'end':>8} {'growth':>8}"]
    first = next((s for s in samples if s["t"] >= 60.0), None)
    for n in names:
        if first is None or first.get(n) is None:
            continue
        end = next((s[n] for s in reversed(samples) if s.get(n) is not None), None)
        lines.append(f"{n:10} {first[n]:8.0f} {end:8.0f} {end - first[n]:+8.0f}")
    return "\n".join(lines)


if __name__ == "__main__":
    sys.exit(main())
