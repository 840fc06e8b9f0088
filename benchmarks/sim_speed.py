"""Real-time factor and peak memory of the PyBullet world.

Three robots wander the field (a reactive controller on their laser scans),
commanded at 10 Hz with a laser scan each at 10 Hz, for ``--seconds`` of sim
time:

- ``oracle``: oracle detections at 2 Hz per robot (no rendering);
- ``rendered``: camera images at 2 Hz per robot (TinyRenderer, 320x240 by
  default).

Each mode runs in its own process pinned to one CPU, so the peak resident
memory (``ru_maxrss``) and the speed belong to that mode alone.

    .venv/bin/python benchmarks/sim_speed.py [--seconds 60] [--modes oracle,rendered]
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


def run_mode(mode: str, seconds: float, robots: int, width: int, height: int, seed: int) -> dict:
    if hasattr(os, "sched_setaffinity"):
        os.sched_setaffinity(0, {sorted(os.sched_getaffinity(0))[0]})
    from backends.sim import SimBackend, World
    world = World("rcll2016", seed=seed, perception="oracle" if mode == "oracle" else "rendered")
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
    ap.add_argument("--modes", default="oracle,rendered")
    ap.add_argument("--size", default="320x240", help="camera resolution in rendered mode")
    ap.add_argument("--seed", type=int, default=0)
    args = ap.parse_args(argv)
    try:
        width, height = (int(v) for v in args.size.lower().split("x"))
    except ValueError:
        ap.error(f"--size must look like 320x240, not {args.size!r}")
    modes = [m.strip() for m in args.modes.split(",") if m.strip()]
    bad = [m for m in modes if m not in ("oracle", "rendered")]
    if bad or args.seconds <= 0 or args.robots < 1:
        ap.error(f"bad modes {bad}" if bad else "--seconds and --robots must be positive")
    ctx = mp.get_context("spawn")
    rows = []
    for mode in modes:
        print(f"running {mode}: {args.seconds:g} sim s, {args.robots} robots ...", file=sys.stderr, flush=True)
        with ctx.Pool(1) as pool:
            rows.append(pool.apply(run_mode, (mode, args.seconds, args.robots, width, height, args.seed)))
    print(f"\nPyBullet RCLL world, {args.robots} robots, lasers 10 Hz (240 beams), commands 10 Hz, "
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
    return 0


if __name__ == "__main__":
    sys.exit(main())
