"""Machine poses from station tags on rendered PyBullet images.

Run: .venv/bin/python benchmarks/machine_pose.py [--views 240] [--seed 0]

A robot with a 640x480 camera (0.57 m high, level) is put in front of a
station face, 0.6-2.5 m from it, up to 45 degrees off its normal and
looking roughly at the tag; only views where the world's oracle says the
tag is in view (its centre and four corners unoccluded) are kept.  Each view
is rendered (backends.sim.camera: the hall behind, under random lighting
unless --lighting default), the tag is found and its pose solved (skills.perception.tags),
and the station's centre is computed from the tag through the camera
extrinsics and the true robot pose.  Printed: single-view errors (position,
orientation), zone and discrete rotation correct, by distance band, and the
same for the Kalman tracker fed with all views of each station.
"""
from __future__ import annotations

import argparse
import math
import time

import numpy as np

from backends.sim import World
from backends.sim.render import Lighting
from rll_bt.backend import Pose2D, wrap_angle
from skills.perception.tags import MachineTracker, TagDetector, machine_pose_from_tag, tag_in_field

BANDS = ((0.6, 1.2), (1.2, 1.8), (1.8, 2.5))


def views_of(world: World, rng: np.random.Generator, count: int):
    """(station, side, robot pose, distance) of random views of station faces."""
    out = []
    names = world.machines
    tries = 0
    while len(out) < count and tries < count * 30:
        tries += 1
        st = world.station(names[int(rng.integers(len(names)))])
        side = "input" if rng.random() < 0.5 else "output"
        centre, frame = st.tag_frame(side)
        normal = math.atan2(frame[1, 2], frame[0, 2])
        d = rng.uniform(0.6, 2.5)
        a = normal + math.radians(rng.uniform(-45, 45))
        cam_x, cam_y = centre[0] + d * math.cos(a), centre[1] + d * math.sin(a)
        heading = math.atan2(centre[1] - cam_y, centre[0] - cam_x) + math.radians(rng.uniform(-12, 12))
        # the camera sits 0.2 m ahead of the robot centre
        pose = Pose2D(cam_x - 0.2 * math.cos(heading), cam_y - 0.2 * math.sin(heading), wrap_angle(heading))
        world.teleport("CYAN", 1, pose)
        if world.clearance("CYAN", 1) < 0.02:
            continue
        tag_id = st.tag_id(side)
        seen = world.detections(world.robot("CYAN", 1))
        if tag_id not in [t.tag_id for t in seen.tags]:
            continue
        out.append((st, side, pose, d))
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--views", type=int, default=240, help="rendered views in all (default 240)")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--lighting", choices=("random", "default"), default="random",
                    help="light every view at random (colour temperature, direction, exposure) or as the default")
    args = ap.parse_args()
    rng = np.random.default_rng(args.seed)
    rows = []            # (distance, pos err, yaw err deg, zone ok, rotation ok, detected)
    tracked = []
    t0 = time.perf_counter()
    per_world = max(1, args.views // 4)
    for k, profile in enumerate(("rcll2016", "rcll2025", "rcll2016", "rcll2025")):
        with World(profile, seed=args.seed * 10 + k, perception="rendered") as world:
            world.add_robot("CYAN", 1, camera_width=640, camera_height=480)
            prof = world.profile
            det = TagDetector(prof.tag_size, valid_ids=set(prof.all_tag_ids))
            tracker = MachineTracker(prof)
            robot = world.robot("CYAN", 1)
            for st, side, pose, d in views_of(world, rng, per_world):
                world.teleport("CYAN", 1, pose)
                world.step(0.02)
                if args.lighting == "random":
                    world.set_lighting(Lighting.random(rng))
                img = world.camera_image(robot)
                up = img.extrinsics.rotation().T @ np.array([0.0, 0.0, 1.0])
                tags = [t for t in det.detect(img.image, img.intrinsics, up=up) if t.tag_id == st.tag_id(side)]
                if not tags:
                    rows.append((d, math.nan, math.nan, False, False, False))
                    continue
                owner = prof.machine_for_tag(tags[0].tag_id)
                est = machine_pose_from_tag(tag_in_field(tags[0], img.extrinsics, world.robot_pose("CYAN", 1)),
                                            owner[1], prof.mps)
                truth = st.pose
                err = est.distance_to(truth)
                yaw = abs(math.degrees(wrap_angle(est.theta - truth.theta)))
                zone_ok = prof.zone_at(est.x, est.y) == st.zone
                rot_ok = prof.discretise_rotation(math.degrees(est.theta)) == st.rotation % 360
                rows.append((d, err, yaw, zone_ok, rot_ok, True))
                tracker.add(tags[0], img.extrinsics, world.robot_pose("CYAN", 1))
            for name, e in tracker.estimates().items():
                st = world.station(name)
                tracked.append((e.sightings, e.pose.distance_to(st.pose),
                                abs(math.degrees(wrap_angle(e.pose.theta - st.pose.theta))),
                                e.zone == st.zone, e.rotation_deg == st.rotation % 360))
    seconds = time.perf_counter() - t0
    arr = np.array(rows, dtype=float)
    print(f"machine pose from tags: {len(rows)} rendered 640x480 views ({args.lighting} lighting), "
          f"{seconds:.0f} s\n")
    print(f"{'views':<14} {'n':>5} {'detected':>9} {'pos med cm':>11} {'pos p90 cm':>11} "
          f"{'yaw med deg':>12} {'yaw p90 deg':>12} {'zone ok':>8} {'rot ok':>7}")

    def line(label, sel):
        sub = arr[sel]
        ok = sub[sub[:, 5] == 1]
        if len(ok) == 0:
            print(f"{label:<14} {len(sub):>5} {'0':>9}")
            return
        print(f"{label:<14} {len(sub):>5} {len(ok) / len(sub):>9.3f} {np.median(ok[:, 1]) * 100:>11.2f} "
              f"{np.percentile(ok[:, 1], 90) * 100:>11.2f} {np.median(ok[:, 2]):>12.2f} "
              f"{np.percentile(ok[:, 2], 90):>12.2f} {ok[:, 3].mean():>8.3f} {ok[:, 4].mean():>7.3f}")
    line("all", np.ones(len(arr), bool))
    for lo, hi in BANDS:
        line(f"{lo:.1f}-{hi:.1f} m", (arr[:, 0] >= lo) & (arr[:, 0] < hi))
    if tracked:
        t = np.array(tracked, dtype=float)
        print(f"\ntracker (Kalman filter per station over its views): {len(t)} stations, "
              f"median {np.median(t[:, 0]):.0f} views each")
        print(f"  position error median {np.median(t[:, 1]) * 100:.2f} cm, max {t[:, 1].max() * 100:.2f} cm; "
              f"yaw error median {np.median(t[:, 2]):.2f} deg, max {t[:, 2].max():.2f} deg; "
              f"zone correct {t[:, 3].mean():.3f}; rotation correct {t[:, 4].mean():.3f}")
    print("\naims: median position error <= 5 cm, orientation <= 5 deg, zone correct 100 %")


if __name__ == "__main__":
    main()
