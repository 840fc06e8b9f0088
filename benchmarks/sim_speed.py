"""Real-time factor and peak memory of the PyBullet world, and of whole games.

World modes: three robots wander the field (a reactive controller on their
laser scans), commanded at 10 Hz with a laser scan each at 10 Hz, for
``--seconds`` of sim time:

- ``oracle``: oracle detections at 2 Hz per robot (no rendering);
- ``rendered``: camera images at 2 Hz per robot (TinyRenderer, 320x240 by
  default, every frame rendered whole).

Game modes: a whole lockstep game (``rll-bt sim``'s, seed ``--seed``,
rules ``--profile``, SETUP shortened to 1 s; ``--game-until exploration``
stops after the exploration phase): refbox, world, team server and three
agents with their trees, localisation and navigation, on one simulated clock:

- ``game-oracle``: the simulator hands over the tags and lights in view;
- ``game-rendered``: every robot's camera frames (320x240, at most 5 per
  second, rendered where stations can be detected: ``backends.sim.sparse``)
  go through the tag detector and the light reader.

Each mode runs in its own process pinned to one CPU, so the peak resident
memory (``ru_maxrss``) and the speed belong to that mode alone; a game's
wall time counts the game from its first round (building the world and
loading the trees before it are not counted).

    .venv/bin/python benchmarks/sim_speed.py [--seconds 60] [--modes oracle,rendered,game-oracle,game-rendered]
"""
from __future__ import annotations

import argparse
import math
import multiprocessing as mp
import os
import resource
import sys
import time

import numpy as np


def _controller(scan, k: int, i: int) -> tuple[float, float, float]:
    """Drive forward, veer gently, turn away from anything closer than 0.8 m ahead."""
    ahead = scan.ranges[np.abs(scan.angles) < 0.5]
    if ahead.size and ahead.min() < 0.8:
        return (0.0, 0.0, 1.2 if i % 2 else -1.2)
    return (0.6, 0.0, 0.3 * math.sin(0.05 * k + i))


MODES = ("oracle", "rendered", "game-oracle", "game-rendered")


def _pin() -> None:
    if hasattr(os, "sched_setaffinity"):
        os.sched_setaffinity(0, {sorted(os.sched_getaffinity(0))[0]})


def run_game(mode: str, profile: str, seed: int, until: str) -> dict:
    """A whole lockstep game with ``mode``'s perception; the numbers of :func:`main`'s table."""
    _pin()
    from games.lockstep import LockstepGame
    from games.options import GameOptions
    opts = GameOptions(profile=profile, seed=seed, perception=mode.split("-")[1], until=until, setup=1.0)
    with LockstepGame(opts) as game:
        world = game.world.pybullet                   # the PyBullet world behind the contract
        frames = {"n": 0}
        if mode == "game-rendered":
            render = world.render_view

            def counted(*args, **kwargs):
                frames["n"] += 1
                return render(*args, **kwargs)
            world.render_view = counted
        cpu0, t0 = time.process_time(), time.perf_counter()
        res = game.run()
        wall, cpu = time.perf_counter() - t0, time.process_time() - cpu0
        st = res.status
        points = st.points.get("CYAN", 0) if hasattr(st, "points") else 0
    return dict(mode=mode, sim=res.sim_time, wall=wall, cpu=cpu, rtf=res.sim_time / wall, points=points,
                renders=frames["n"], collisions=res.collisions,
                peak_mb=resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0)


def run_mode(mode: str, seconds: float, robots: int, width: int, height: int, seed: int) -> dict:
    _pin()
    from backends.sim import SimBackend, World
    world = World("rcll2016", seed=seed, perception="oracle" if mode == "oracle" else "rendered")
    world.sparse_camera = False
    bots = [SimBackend(world, ("CYAN", n), camera_width=width, camera_height=height)
            for n in range(1, robots + 1)]
    scans = images = detections = 0
    ticks = int(round(seconds * 10))
    t0 = time.perf_counter()
    for k in range(ticks):
        for i, bot in enumerate(bots):
            scan = bot.laser_scan()
            scans += 1
            bot.drive(*_controller(scan, k, i))
            if k % 5 == 0:
                if mode == "oracle":
                    bot.detections()
                    detections += 1
                else:
                    bot.camera_image()
                    images += 1
        world.step(0.1)
    wall = time.perf_counter() - t0
    result = {"mode": mode, "sim": world.time, "wall": wall, "rtf": world.time / wall, "scans": scans,
                  "images": images, "detections": detections, "collisions": world.collision_count,
                  "distance": sum(b.robot.distance for b in bots),
                  "peak_mb": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0,
                  "substeps": int(round(world.time / world.time_step))}
    world.close()
    return result


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--seconds", type=float, default=60.0, help="sim seconds per mode (default 60)")
    ap.add_argument("--robots", type=int, default=3)
    ap.add_argument("--modes", default="oracle,rendered",
                    help=f"comma-separated, of {', '.join(MODES)} (default oracle,rendered)")
    ap.add_argument("--size", default="320x240", help="camera resolution in rendered mode")
    ap.add_argument("--seed", type=int, default=0, help="world seed (games: the game's seed, default 1)")
    ap.add_argument("--profile", default="rcll2016", help="rules of the game modes (default rcll2016)")
    ap.add_argument("--game-until", default="end", choices=("exploration", "end"),
                    help="game modes: play to the end (default) or stop after exploration")
    args = ap.parse_args(argv)
    try:
        width, height = (int(v) for v in args.size.lower().split("x"))
    except ValueError:
        ap.error(f"--size must look like 320x240, not {args.size!r}")
    modes = [m.strip() for m in args.modes.split(",") if m.strip()]
    bad = [m for m in modes if m not in MODES]
    if bad or args.seconds <= 0 or args.robots < 1:
        ap.error(f"bad modes {bad}" if bad else "--seconds and --robots must be positive")
    ctx = mp.get_context("spawn")
    rows, games = [], []
    for mode in modes:
        with ctx.Pool(1) as pool:
            if mode.startswith("game-"):
                print(f"running {mode}: a whole {args.profile} game ...", file=sys.stderr, flush=True)
                games.append(pool.apply(run_game, (mode, args.profile, args.seed or 1, args.game_until)))
            else:
                print(f"running {mode}: {args.seconds:g} sim s, {args.robots} robots ...", file=sys.stderr, flush=True)
                rows.append(pool.apply(run_mode, (mode, args.seconds, args.robots, width, height, args.seed)))
    if rows:
        print_world(rows, args.robots, width, height)
    if games:
        print_games(games, args.profile, args.seed or 1, args.game_until)
    return 0


def print_games(games: list[dict], profile: str, seed: int, until: str) -> None:
    print(f"\nwhole lockstep games, {profile} seed {seed}, 3 robots, SETUP 1 s, "
          f"{'to the end' if until == 'end' else 'exploration only'}, one CPU")
    head = f"{'mode':14} {'sim s':>7} {'wall s':>7} {'CPU s':>7} {'RTF':>6} {'renders':>8} {'points':>6} " \
           f"{'peak RSS MB':>11}"
    print(head)
    print("-" * len(head))
    for g in games:
        print(f"{g['mode']:14} {g['sim']:7.1f} {g['wall']:7.1f} {g['cpu']:7.1f} {g['rtf']:6.1f} {g['renders']:8d} "
              f"{g['points']:6d} {g['peak_mb']:11.1f}")
    print("\nRTF = game seconds per wall second; renders = TinyRenderer calls (a frame is one or more: "
          "backends.sim.sparse); points = the team's score.")


def print_world(rows: list[dict], robots: int, width: int, height: int) -> None:
    print(f"\nPyBullet RCLL world, {robots} robots, lasers 10 Hz (240 beams), commands 10 Hz, "
          f"step {0.02:g} s, one CPU")
    head = f"{'mode':9} {'sim s':>7} {'wall s':>7} {'RTF':>7} {'scans':>6} {'camera':>14} " \
           f"{'collisions':>10} {'driven m':>9} {'peak RSS MB':>11}"
    print(head)
    print("-" * len(head))
    for r in rows:
        cam = (f"{r['images']} img {width}x{height}" if r["mode"] == "rendered"
               else f"{r['detections']} oracle")
        print(f"{r['mode']:9} {r['sim']:7.1f} {r['wall']:7.2f} {r['rtf']:7.1f} {r['scans']:6d} {cam:>14} "
              f"{r['collisions']:10d} {r['distance']:9.1f} {r['peak_mb']:11.1f}")
    print("\nRTF = sim seconds per wall second; camera = images at 2 Hz per robot "
          "(rendered) or oracle detection calls at 2 Hz per robot.")


if __name__ == "__main__":
    sys.exit(main())
