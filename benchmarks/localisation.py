"""Accuracy and cost of the Monte Carlo localiser (skills.localisation).

Run: .venv/bin/python benchmarks/localisation.py [--seeds 3] [--world sim|flat]

A robot drives a tour of station approach poses in the PyBullet world (or
the flat test world), steered on ground truth so every configuration sees
the same motion; each configuration's localiser runs passively on the
robot's odometry and laser, starting from the true pose with a 0.1 m /
0.1 rad spread.  Errors are against the world's ground truth at every
filter update after the first 5 s; the time is the wall clock of one
filter update (predict, weigh, resample, estimate), measured here.
Aims (issue 6): median position error 5 cm, heading 2 degrees, 10 ms per
update with 500 particles and 60 beams.

``--relocalise N``: N kidnapped-robot trials per seed instead (issue 9).  A
robot stands at a random free spot of the PyBullet field; its localiser
(the ``cheap`` preset of whole games) is confidently wrong: off by up to
1 m and 60 degrees ("near"), or anywhere on the field ("anywhere"); then
the tree's ``common/relocalise.yaml`` runs (relocalise around the last
pose, then globally), with the oracle's tag sightings or without any
tags.  Reported: how often it ends at the true pose (within 10 cm and 0.1
rad), how often it reports LOCALISATION_LOST, how often it wrongly
reports success (the case that must not happen), and the simulated time
it takes.
"""
from __future__ import annotations

import argparse
import math
import sys
import time

import numpy as np

from rll_bt import rules
from rll_bt.backend import Pose2D, open_backend, wrap_angle
from skills.activity import Status
from skills.context import FunctionPose, SkillContext
from skills.localisation import AmclConfig, Localiser
from skills.maps import FieldMap
from skills.navigation import Navigate, StationSideGoal

CONFIGS = {
    "fixed 500 / 60 beams": AmclConfig.fixed(500, 60),
    "standard (KLD 100..1000, 60 beams)": AmclConfig.standard(),
    "cheap (KLD 60..300, 24 beams)": AmclConfig.cheap(),
}


def sim_scene(seed):
    from backends.sim import World
    world = World("rcll2016", seed=seed)
    bot = open_backend("sim", world=world, robot=("CYAN", 1))
    truth = lambda: world.robot_pose("CYAN", 1)  # noqa: E731
    stations = {n: st.pose for n, st in world.stations.items()}
    return world, bot, truth, stations, world.step


def flat_scene(seed):
    from skills.testing import FlatWorld
    prof = rules.profile()
    world = FlatWorld.from_profile(prof, seed=seed)
    rng = np.random.default_rng(seed)
    stations = {}
    for name in ("C-BS", "C-CS1", "C-RS1", "C-DS"):
        zone = prof.fixed_zones.get(name) or int(rng.choice([z for z in range(1, 13) if z not in (9, 4)]))
        x, y = prof.zone_centre(zone)
        stations[name] = Pose2D(x, y, math.radians(45 * int(rng.integers(0, 8))))
        world.add_station(name, stations[name], prof.tag_ids(name))
    bot = world.add_robot(Pose2D(4.5, -0.5, math.pi / 2))

    def step(dt):
        n = max(1, round(dt / 0.05))
        for _ in range(n):
            world.step(dt / n)
    return world, bot, lambda: bot.true_pose, stations, step


def tour(stations):
    names = [n for n in sorted(stations) if n.startswith("C-")]
    return [StationSideGoal(n, side, 0.8) for n in names for side in ("INPUT", "OUTPUT")
            if n[2:4] != "DS" or side == "INPUT"]


def run(seed, world_kind, results):
    world, bot, truth, stations, step = (sim_scene if world_kind == "sim" else flat_scene)(seed)
    prof = rules.profile()
    fmap = FieldMap.from_profile(prof)
    for n, p in stations.items():
        fmap.add_station(n, p)
    ctx = SkillContext(bot, world.clock, prof, fmap, FunctionPose(truth))
    for n, p in stations.items():
        ctx.machines.set(n, p, confirm=False)
    locs = {}
    for i, (name, cfg) in enumerate(CONFIGS.items()):
        loc = Localiser(bot, fmap, world.clock, cfg, seed=seed * 10 + i)
        loc.initialise(truth(), (0.1, 0.1, 0.1))
        locs[name] = loc
    t_start = world.clock.now()
    for goal in tour(stations):
        nav = Navigate(ctx, goal, timeout=60.0).start()
        while nav.poll() is Status.RUNNING:
            step(0.1)
            for name, loc in locs.items():
                t0 = time.perf_counter()
                ran = loc.update()
                dt = time.perf_counter() - t0
                if not ran:
                    continue
                r = results.setdefault(name, {"pos": [], "head": [], "ms": [], "n": [], "lost": 0})
                r["ms"].append(dt * 1e3)
                if world.clock.now() - t_start < 5.0:
                    continue
                est, t = loc.estimate(), truth()
                r["pos"].append(math.hypot(est.pose.x - t.x, est.pose.y - t.y))
                r["head"].append(abs(wrap_angle(est.pose.theta - t.theta)))
                r["n"].append(est.particles)
                r["lost"] += int(est.lost)
    return world.clock.now() - t_start


class _NoTags:
    def detections(self):
        return None


def relocalise_trial(seed, rng, far: bool, tags: bool) -> dict:
    """One kidnapped-robot trial; see the module doc."""
    from backends.sim import World
    from skills.localisation.relocalise import Relocalise
    world = World("rcll2016", seed=seed)
    f = world.profile.field
    while True:
        x, y = rng.uniform(f.x_min + 0.6, f.x_max - 0.6), rng.uniform(f.y_min + 0.6, f.y_max - 0.6)
        if all(st.box.sdf(x, y) > 0.5 for st in world.stations.values()):
            break
    truth = Pose2D(x, y, rng.uniform(-math.pi, math.pi))
    if far:
        while True:
            bx, by = rng.uniform(f.x_min + 0.6, f.x_max - 0.6), rng.uniform(f.y_min + 0.6, f.y_max - 0.6)
            if all(st.box.sdf(bx, by) > 0.3 for st in world.stations.values()):
                break
        believed = Pose2D(bx, by, rng.uniform(-math.pi, math.pi))
    else:
        r, a = rng.uniform(0.3, 1.0), rng.uniform(-math.pi, math.pi)
        believed = Pose2D(x + r * math.cos(a), y + r * math.sin(a), truth.theta + rng.uniform(-1.05, 1.05))
    bot = open_backend("sim", world=world, robot=("CYAN", 1), pose=truth)
    ctx = SkillContext.create(bot, world.clock, world.profile, believed, localisation="cheap", seed=seed)
    for n, st in world.stations.items():
        ctx.machines.set(n, st.pose)
    if not tags:
        ctx.tags = _NoTags()
    ctx.pose_source.initialise(believed, (0.02, 0.02, 0.02))
    t0 = world.time
    status = Status.FAILURE
    for global_search in (False, True):
        status = Relocalise(ctx, global_search=global_search).run(0.1, advance=world.step, limit=60.0)
        if status is Status.SUCCESS:
            break
    p, t = ctx.pose(), world.robot_pose("CYAN", 1)
    right = math.hypot(p.x - t.x, p.y - t.y) < 0.1 and abs(wrap_angle(p.theta - t.theta)) < 0.1
    world.close()
    return {"ok": status is Status.SUCCESS and right, "wrong": status is Status.SUCCESS and not right,
            "lost": status is not Status.SUCCESS, "time": world.clock.now() - t0}


def relocalise_table(seeds: int, trials: int) -> None:
    rows = []
    for seed in range(1, seeds + 1):
        print(f"seed {seed}/{seeds} ...", file=sys.stderr, flush=True)
        rng = np.random.default_rng(seed)
        for far in (False, True):
            for tags in (True, False):
                for _ in range(trials):
                    rows.append(dict(relocalise_trial(seed, rng, far, tags), far=far, tags=tags))
    print(f"\nrelocalising a kidnapped robot (PyBullet world, cheap preset), {seeds} layouts x {trials} trials\n")
    head = f"{'believed pose':14} {'tags':>5} {'trials':>7} {'right':>6} {'lost':>5} {'wrong':>6} {'time med':>9}"
    print(head)
    print("-" * len(head))
    for far in (False, True):
        for tags in (True, False):
            sel = [r for r in rows if r["far"] == far and r["tags"] == tags]
            print(f"{'anywhere' if far else '<= 1 m off':14} {'yes' if tags else 'no':>5} {len(sel):7d} "
                  f"{sum(r['ok'] for r in sel):6d} {sum(r['lost'] for r in sel):5d} {sum(r['wrong'] for r in sel):6d} "
                  f"{np.median([r['time'] for r in sel]):8.1f}s")
    print("\nright: ends within 10 cm / 0.1 rad of the truth; lost: reports LOCALISATION_LOST; "
          "wrong: reports success at a wrong pose")


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, default=3, help="number of field layouts (seeds 1..N)")
    ap.add_argument("--world", choices=("sim", "flat"), default="sim",
                    help="PyBullet world (default) or the flat 2D test world")
    ap.add_argument("--relocalise", type=int, metavar="N", default=0,
                    help="run N kidnapped-robot trials per seed and case instead of the driving tour")
    args = ap.parse_args()
    if args.relocalise:
        relocalise_table(args.seeds, args.relocalise)
        return 0
    results: dict = {}
    sim_time = 0.0
    for seed in range(1, args.seeds + 1):
        print(f"seed {seed}/{args.seeds} ...", file=sys.stderr, flush=True)
        sim_time += run(seed, args.world, results)
    print(f"\nlocalisation on the {args.world} world, {args.seeds} layouts, {sim_time:.0f} s of driving\n")
    head = f"{'configuration':36} {'pos med':>8} {'pos p95':>8} {'head med':>9} {'head p95':>9} " \
           f"{'ms med':>7} {'ms p95':>7} {'updates':>8} {'particles':>9} {'lost':>5}"
    print(head)
    print("-" * len(head))
    for name, r in results.items():
        pos, hd, ms = np.array(r["pos"]) * 100, np.degrees(r["head"]), np.array(r["ms"])
        print(f"{name:36} {np.median(pos):6.1f}cm {np.percentile(pos, 95):6.1f}cm "
              f"{np.median(hd):7.2f}deg {np.percentile(hd, 95):7.2f}deg {np.median(ms):7.2f} "
              f"{np.percentile(ms, 95):7.2f} {len(ms):8d} {int(np.median(r['n'])):9d} {r['lost']:5d}")
    print("\naims: median position error <= 5 cm, heading <= 2 deg, <= 10 ms per update at 500 particles / 60 beams")
    return 0


if __name__ == "__main__":
    sys.exit(main())
