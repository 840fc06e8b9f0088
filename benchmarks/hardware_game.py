"""Whole games through emulated hardware beside the same seeds on the sim backend.

    .venv/bin/python benchmarks/hardware_game.py --seeds 5
    .venv/bin/python benchmarks/hardware_game.py --seeds 2 --production 300   # shorter games
    # both kinds side by side, then the table of what was kept:
    .venv/bin/python benchmarks/hardware_game.py --only hardware --out DIR &
    .venv/bin/python benchmarks/hardware_game.py --only sim --out DIR
    .venv/bin/python benchmarks/hardware_game.py --table --out DIR

For every seed two games of the 2016 rules, three robots:

* ``hardware``: ``rll-bt sim --hardware emulated``, every agent on the
  robotino backend over device emulators fed by the world (base firmware
  and gripper on ptys, an URG or TiM laser, an MJPEG camera), each part its
  own process on the wall clock, perception on the camera frames;
* ``sim``: the same seed on the sim backend, by default in lockstep with
  rendered perception (the same detectors on the world's renders, so the
  two differ by the hardware path and the wall clock), or ``--against
  processes`` (sim backend in processes on the wall clock, same perception
  setting).

Printed: points (exploration, production, total) of both, the hardware
game's share of the sim game's points, collisions, and per robot of the
hardware game the serial poll rate, laser scans and camera frames per
second, the base's watchdog stops and how often the emulator's thread was
late (a read more than 100 ms after the one before: the world process is
busy), and how far the world stood behind the wall clock (more than 0.5 s:
no laser casts, no camera frames).  The aim (issue 18): within 10 % of
the sim backend's points on every seed, 0 watchdog stops.  A hardware game
takes its real length (about 20 minutes for a whole 2016 game).
"""
from __future__ import annotations

import argparse
import json
import sys
import tempfile
import time
from pathlib import Path

from backends.robotino.rig import LASERS


def play(opts, out: Path, connect_timeout: float) -> dict:
    import time as _time

    from games import finish, sigterm_interrupts
    from games import play as play_game
    opts.out = out
    out.mkdir(parents=True, exist_ok=True)
    if opts.hardware != "emulated":
        return play_game(opts)
    from games.hardware import HardwareGame  # as play() does, with a longer wait for the processes
    t0 = _time.monotonic()
    with sigterm_interrupts():         # kill PID stops the game's processes too
        game = HardwareGame(opts, connect_timeout=connect_timeout)
        try:
            result = game.run()
        finally:
            game.close()
    return finish(result, opts, _time.monotonic() - t0)


def print_table(rows, args, wall: float) -> None:
    print(f"hardware games (rll-bt sim --hardware emulated, laser {args.laser}) beside the sim backend "
          f"({args.against}, perception {args.perception}); rcll2016, 3 robots; {wall:.0f} s wall")
    print()
    print(f"{'seed':>4} {'sim expl':>8} {'sim prod':>8} {'sim total':>9} {'hw expl':>8} {'hw prod':>8} "
          f"{'hw total':>8} {'hw/sim':>7} {'coll sim':>8} {'coll hw':>7}")
    within = True
    for seed, hw, sim in rows:
        if hw is None or sim is None:
            print(f"{seed:4d}   (not played: {'hardware' if hw is None else 'sim'} game missing)")
            within = False
            continue
        s_tot, h_tot = sim["points"]["total"], hw["points"]["total"]
        ratio = h_tot / s_tot if s_tot else float("nan")
        within &= s_tot == 0 or abs(ratio - 1.0) <= 0.10
        print(f"{seed:4d} {sim['points']['exploration']:8d} {sim['points']['production']:8d} {s_tot:9d} "
              f"{hw['points']['exploration']:8d} {hw['points']['production']:8d} {h_tot:8d} {ratio:7.2f} "
              f"{sim['collisions']:8d} {hw['collisions']:7d}")
    print()
    print(f"{'seed':>4} {'robot':>7} {'serial polls/s':>14} {'scans/s':>8} {'frames/s':>9} {'watchdog stops':>15} "
          f"{'emu stalls':>10} {'longest s':>9}")
    stops = 0
    for seed, hw, _ in rows:
        for name, h in sorted((hw or {}).get("hardware_stats", {}).items()):
            stops += h["watchdog_motion_stops"]
            print(f"{seed:4d} {name:>7} {h['serial_polls_per_s']:14.1f} {h['scans_per_s']:8.2f} "
                  f"{h['frames_per_s']:9.2f} {h['watchdog_motion_stops']:15d} "
                  f"{h.get('emulator_stalls', 0):10d} {h.get('longest_stall_s', 0.0):9.3f}")
    print()
    for seed, hw, _ in rows:
        lag = (hw or {}).get("world_lag")
        if lag:
            print(f"seed {seed}: the world behind the wall clock at most {lag['longest_s']:.2f} s, more than "
                  f"{lag['stale_above_s']:g} s (no casts, no frames) for {lag['stale_s']:.1f} s in "
                  f"{lag['stale_spells']} spells")
    print()
    print(f"within 10 % of the sim backend's points on every seed: {'yes' if within else 'NO'}; "
          f"watchdog stops while moving: {stops}")


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--seeds", type=int, default=5, help="seeds 1..N (default 5)")
    ap.add_argument("--first-seed", type=int, default=1)
    ap.add_argument("--exploration", type=float, default=None, metavar="S", help="exploration length (rules')")
    ap.add_argument("--production", type=float, default=None, metavar="S", help="production length (rules')")
    ap.add_argument("--laser", choices=LASERS, default="urg")
    ap.add_argument("--against", choices=("lockstep", "processes"), default="lockstep",
                    help="how the sim-backend game runs (default lockstep)")
    ap.add_argument("--perception", choices=("rendered", "oracle"), default="rendered",
                    help="perception of the sim-backend game (default rendered, as the hardware's camera)")
    ap.add_argument("--out", type=Path, default=None, help="keep every game's files here")
    ap.add_argument("--only", choices=("hardware", "sim"), default=None,
                    help="play only one kind of game (run both kinds side by side, then --table)")
    ap.add_argument("--table", action="store_true",
                    help="print the table of the games kept in --out (seed*-hardware.json, seed*-sim.json)")
    ap.add_argument("--connect-timeout", type=float, default=300.0, metavar="S",
                    help="how long the hardware game waits for its processes to come up (default 300)")
    args = ap.parse_args(argv)
    if args.table and args.out is None:
        ap.error("--table needs --out")
    from games import GameOptions

    out = args.out or Path(tempfile.mkdtemp(prefix="hardware-game-"))
    seeds = range(args.first_seed, args.first_seed + args.seeds)
    t0 = time.monotonic()
    for seed in ([] if args.table else seeds):
        common = dict(profile="rcll2016", seed=seed, exploration=args.exploration, production=args.production)
        for kind in ("hardware", "sim"):
            if args.only not in (None, kind):
                continue
            if kind == "hardware":
                print(f"seed {seed}: hardware game ...", file=sys.stderr, flush=True)
                opts = GameOptions(hardware="emulated", processes=True, laser=args.laser, **common)
            else:
                print(f"seed {seed}: sim-backend game ({args.against}, {args.perception}) ...", file=sys.stderr,
                      flush=True)
                opts = GameOptions(processes=args.against == "processes", perception=args.perception, **common)
            res = play(opts, out / f"seed{seed}-{kind}", args.connect_timeout)
            res.pop("table", None)
            (out / f"seed{seed}-{kind}.json").write_text(json.dumps(res, indent=1, default=str))
            print(f"seed {seed}: {kind} {res['points']['total']} points; kept in {out / f'seed{seed}-{kind}.json'}",
                  file=sys.stderr, flush=True)

    def load(seed, kind):
        f = out / f"seed{seed}-{kind}.json"
        return json.loads(f.read_text()) if f.exists() else None
    rows = [(seed, load(seed, "hardware"), load(seed, "sim")) for seed in seeds]
    print_table(rows, args, time.monotonic() - t0)
    print(f"games kept in {out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
