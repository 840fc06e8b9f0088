"""Whole games through emulated hardware beside the same seeds on the sim backend.

    .venv/bin/python benchmarks/hardware_game.py --seeds 5
    .venv/bin/python benchmarks/hardware_game.py --seeds 2 --production 300   # shorter games

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
busy).  The aim (issue 18): within 10 % of
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


def play(opts, out: Path) -> dict:
    from games import play as play_game
    opts.out = out
    out.mkdir(parents=True, exist_ok=True)
    return play_game(opts)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--seeds", type=int, default=5, help="seeds 1..N (default 5)")
    ap.add_argument("--first-seed", type=int, default=1)
    ap.add_argument("--exploration", type=float, default=None, metavar="S", help="exploration length (rules')")
    ap.add_argument("--production", type=float, default=None, metavar="S", help="production length (rules')")
    ap.add_argument("--laser", choices=("urg", "tim"), default="urg")
    ap.add_argument("--against", choices=("lockstep", "processes"), default="lockstep",
                    help="how the sim-backend game runs (default lockstep)")
    ap.add_argument("--perception", choices=("rendered", "oracle"), default="rendered",
                    help="perception of the sim-backend game (default rendered, as the hardware's camera)")
    ap.add_argument("--out", type=Path, default=None, help="keep every game's files here")
    args = ap.parse_args(argv)
    from games import GameOptions

    out = args.out or Path(tempfile.mkdtemp(prefix="hardware-game-"))
    rows = []
    t0 = time.monotonic()
    for seed in range(args.first_seed, args.first_seed + args.seeds):
        common = dict(profile="rcll2016", seed=seed, exploration=args.exploration, production=args.production)
        print(f"seed {seed}: hardware game ...", file=sys.stderr, flush=True)
        hw = play(GameOptions(hardware="emulated", processes=True, laser=args.laser, **common),
                  out / f"seed{seed}-hardware")
        print(f"seed {seed}: sim-backend game ({args.against}, {args.perception}) ...", file=sys.stderr, flush=True)
        sim = play(GameOptions(processes=args.against == "processes", perception=args.perception, **common),
                   out / f"seed{seed}-sim")
        rows.append((seed, hw, sim))
        (out / f"seed{seed}.json").write_text(json.dumps({"seed": seed, "hardware": hw, "sim": sim},
                                                         indent=1, default=str))
        print(f"seed {seed}: hardware {hw['points']['total']} points, sim {sim['points']['total']}; "
              f"kept in {out / f'seed{seed}.json'}", file=sys.stderr, flush=True)
    print(f"hardware games (rll-bt sim --hardware emulated, laser {args.laser}) beside the sim backend "
          f"({args.against}, perception {args.perception}); rcll2016, 3 robots; {time.monotonic() - t0:.0f} s wall")
    print()
    print(f"{'seed':>4} {'sim expl':>8} {'sim prod':>8} {'sim total':>9} {'hw expl':>8} {'hw prod':>8} "
          f"{'hw total':>8} {'hw/sim':>7} {'coll sim':>8} {'coll hw':>7}")
    within = True
    for seed, hw, sim in rows:
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
        for name, h in sorted(hw.get("hardware_stats", {}).items()):
            stops += h["watchdog_motion_stops"]
            print(f"{seed:4d} {name:>7} {h['serial_polls_per_s']:14.1f} {h['scans_per_s']:8.2f} "
                  f"{h['frames_per_s']:9.2f} {h['watchdog_motion_stops']:15d} "
                  f"{h.get('emulator_stalls', 0):10d} {h.get('longest_stall_s', 0.0):9.3f}")
    print()
    print(f"within 10 % of the sim backend's points on every seed: {'yes' if within else 'NO'}; "
          f"watchdog stops while moving: {stops}")
    print(f"games kept in {out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
