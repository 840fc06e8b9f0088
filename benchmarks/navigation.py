"""Success rate and speed of navigation (skills.navigation) in the PyBullet world.

Run: .venv/bin/python benchmarks/navigation.py [--seeds 5] [--goals 6] [--others 2] [--localisation standard]

For each field layout (seed) a cyan robot drives to a sequence of random
goals - station sides (0.62 m in front of an input or output face), zone
centres, free poses, none within 0.8 m of a parked robot - while
``--others`` robots stand parked at random free spots the robot does not
know about (it sees them only by laser).  The
robot localises with the given preset (``truth`` uses ground truth).
Reported per goal kind: success rate, collisions, time to goal, and that
time against the straight-line lower bound (distance / 0.7 m/s; a ratio of
1.0 is impossible to beat, detours around stations raise it), and the
closest the robot came to a wall, station or robot (the gap between its
disc and the obstacle, from the world's ground truth) with the goals where
it came closer than 5 cm listed (what, where, how fast).
"""
from __future__ import annotations

import argparse
import math
import random
import sys
import time

import numpy as np

from rll_bt.backend import Pose2D, open_backend
from skills.activity import Status
from skills.context import FunctionPose, SkillContext
from skills.navigation import Navigate, PoseGoal, StationSideGoal, ZoneGoal

MAX_SPEED = 0.7


def free_spot(ctx, rng, margin=0.6):
    f = ctx.profile.field
    for _ in range(1000):
        x, y = rng.uniform(f.x_min + margin, f.x_max - margin), rng.uniform(f.y_min + margin, f.y_max - margin)
        if float(ctx.map.distance(0.05).lookup(np.array([x]), np.array([y]))[0]) > 0.7:
            return x, y
    raise RuntimeError("no free spot")


def random_goal(ctx, rng, kind):
    prof = ctx.profile
    if kind == "station side":
        name = rng.choice([n for n in prof.machines() if n[2:4] != "DS"])
        return StationSideGoal(name, rng.choice(["INPUT", "OUTPUT"]), 0.62)
    if kind == "zone":
        return ZoneGoal(rng.choice(list(prof.zones.all_zones)))
    x, y = free_spot(ctx, rng)
    return PoseGoal(Pose2D(x, y, rng.uniform(-math.pi, math.pi)))


def run_seed(seed, n_goals, n_others, localisation, rows):
    from backends.sim import World
    world = World("rcll2016", seed=seed)
    bot = open_backend("sim", world=world, robot=("CYAN", 1))
    start = world.robot_pose("CYAN", 1)
    if localisation == "truth":
        ctx = SkillContext.create(bot, world.clock, world.profile, start, localisation=None)
        ctx.pose_source = FunctionPose(lambda: world.robot_pose("CYAN", 1))
    else:
        ctx = SkillContext.create(bot, world.clock, world.profile, start, localisation=localisation, seed=seed)
    for n, st in world.stations.items():
        ctx.machines.set(n, st.pose)
    rng = random.Random(seed)
    parked = []
    for k in range(n_others):
        x, y = free_spot(ctx, rng)
        open_backend("sim", world=world, robot=("MAGENTA", k + 1), pose=Pose2D(x, y, rng.uniform(-3, 3)))
        parked.append((x, y))
    kinds = ["station side", "zone", "pose"]
    for i in range(n_goals):
        kind = kinds[i % 3]
        while True:         # a goal a parked robot stands on is not reachable: draw again
            goal = random_goal(ctx, rng, kind)
            target, _ = goal.resolve(ctx)
            if all(math.hypot(target.x - x, target.y - y) > 0.8 for x, y in parked):
                break
        t0, c0, p0 = world.time, world.collision_count, world.robot_pose("CYAN", 1)
        log0 = len(world.collision_log)
        nav = Navigate(ctx, goal).start()
        closest, near = world.closest("CYAN", 1), None
        while nav.poll() is Status.RUNNING:
            world.step(0.1)
            gap = world.closest("CYAN", 1)
            if gap[0] < closest[0]:
                p, v = world.robot_pose("CYAN", 1), world.robot("CYAN", 1).velocity
                closest, near = gap, (p.x, p.y, math.hypot(v[0], v[1]), world.time - t0)
        ok = nav.status is Status.SUCCESS
        target = nav.target or p0
        straight = math.hypot(target.x - p0.x, target.y - p0.y)
        t = world.time - t0
        rows.append({"kind": kind, "ok": ok, "time": t, "bound": straight / MAX_SPEED,
                     "collisions": world.collision_count - c0, "closest": closest[0], "near": (closest[1], near),
                     "error": nav.error.value,
                     "message": nav.message, "seed": seed, "goal": goal.describe(),
                     "hits": [c.obstacle for c in world.collision_log[log0:]]})
        if not ok:      # carry on from wherever the robot is
            pass


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, default=5, help="number of field layouts (seeds 1..N)")
    ap.add_argument("--goals", type=int, default=6, help="goals per layout")
    ap.add_argument("--others", type=int, default=2, help="parked robots unknown to the map")
    ap.add_argument("--localisation", default="standard", choices=("standard", "cheap", "truth"),
                    help="localisation preset, or ground truth")
    args = ap.parse_args()
    rows: list = []
    wall = time.perf_counter()
    for seed in range(1, args.seeds + 1):
        print(f"seed {seed}/{args.seeds} ...", file=sys.stderr, flush=True)
        run_seed(seed, args.goals, args.others, args.localisation, rows)
    wall = time.perf_counter() - wall
    print(f"\nnavigation in the PyBullet world: {args.seeds} layouts x {args.goals} goals, "
          f"{args.others} unknown parked robots, localisation {args.localisation}, {wall:.0f} s wall\n")
    head = f"{'goal kind':14} {'goals':>6} {'success':>8} {'collisions':>10} {'time med':>9} " \
           f"{'bound med':>10} {'ratio med':>10} {'ratio p90':>10} {'gap min':>8} {'< 5 cm':>7}"
    print(head)
    print("-" * len(head))
    for kind in ("station side", "zone", "pose", "all"):
        sel = [r for r in rows if kind == "all" or r["kind"] == kind]
        if not sel:
            continue
        ok = [r for r in sel if r["ok"] and r["bound"] > 0.5]
        ratio = np.array([r["time"] / r["bound"] for r in ok]) if ok else np.array([np.nan])
        print(f"{kind:14} {len(sel):6d} {100.0 * sum(r['ok'] for r in sel) / len(sel):7.0f}% "
              f"{sum(r['collisions'] for r in sel):10d} {np.median([r['time'] for r in sel]):8.1f}s "
              f"{np.median([r['bound'] for r in sel]):9.1f}s {np.median(ratio):10.2f} {np.percentile(ratio, 90):10.2f} "
              f"{100 * min(r['closest'] for r in sel):6.1f}cm {sum(r['closest'] < 0.05 for r in sel):7d}")
    close = [r for r in rows if r["closest"] < 0.05]
    if close:
        print("\ncloser than 5 cm:")
        for r in close:
            what, at = r["near"]
            where = f" at ({at[0]:.2f}, {at[1]:.2f}), {at[2]:.2f} m/s, {at[3]:.1f} s after the start" if at else ""
            print(f"  seed {r['seed']} {r['goal']}: {100 * r['closest']:.1f} cm from {what}{where}")
    failed = [r for r in rows if not r["ok"] or r["collisions"]]
    if failed:
        print("\nfailures and collisions:")
        for r in failed:
            hits = f" (hit {', '.join(r['hits'])})" if r["hits"] else ""
            print(f"  seed {r['seed']} {r['goal']}: {r['error']} {r['message']}{hits}")
    print("\ngap min: the closest the robot came to a wall, station or robot on the way; "
          "< 5 cm: goals where it came closer than 5 cm")
    print("ratio = time to goal / (straight-line distance / 0.7 m/s); goals closer than 0.35 m are left out of it")
    return 0


if __name__ == "__main__":
    sys.exit(main())
