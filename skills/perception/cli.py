"""``rll-bt vision train-light|light|tags``: the perception tools.

- ``train-light --out DIR``: render a labelled data set from the PyBullet
  world, train the tower detector and the light network, report held-out
  accuracy and write the model files (see :mod:`.light.training`).
- ``train-physical --out FILE``: train the physical tower reader (a
  network over what a tower physically is, read in a tag-given region:
  :mod:`.light.physical`) on frames of the PyBullet world or of renderer B.
- ``light IMAGE...``: signal towers and their light states.  With
  ``--json`` one object per image and line: ``{"image": PATH, "ms": float,
  "detections": [{"box": [x, y, w, h], "score": float, "state": 0..7,
  "lights": {"red": "on"|"off", "yellow": ..., "green": ...},
  "probabilities": [8 floats]}]}``, best detection first.
- ``tags IMAGE... --camera FILE``: ArUco tags with their poses in the
  camera frame, and the machine and side each belongs to in the profile.
  The camera file format is documented in :mod:`.camera_file`.

Exit codes: 0 ok, 1 work failed, 2 bad usage or an unreadable input.
"""
from __future__ import annotations

import argparse
import json
import math
import os
import sys

EXIT_OK, EXIT_FAILURE, EXIT_USAGE = 0, 1, 2
#: ``train-light --source``: where training frames come from (:class:`.light.dataset.ChunkSpec`)
SOURCES = {"world": "world", "raycast": "skills.perception.light.unseen.compose:raycast_frames"}


def _int_at_least(lo: int):
    def parse(text: str) -> int:
        try:
            v = int(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"not an integer: {text!r}") from None
        if v < lo:
            raise argparse.ArgumentTypeError(f"must be at least {lo}, not {v}")
        return v
    return parse


def _region(text: str) -> tuple[int, int, int, int]:
    parts = text.split(",")
    try:
        x, y, w, h = (int(float(v)) for v in parts)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected x,y,w,h in pixels, got {text!r}") from None
    if w <= 0 or h <= 0:
        raise argparse.ArgumentTypeError(f"region width and height must be positive, got {text!r}")
    return (x, y, w, h)


def register(cli) -> None:
    sub = cli.group("vision")
    t = sub.add_parser(
        "train-light", help="render a data set from the PyBullet world and train the light models",
        description="Render labelled frames from the PyBullet world (random stations, distances "
                    "0.5-2.5 m, angles, camera heights, lighting: colour temperature, direction, "
                    "intensity, exposure; all 8 light states; the hall behind, often replaced by "
                    "procedural backdrops or photographs), add photometric augmentation and towers "
                    "pasted onto such backdrops, train the HOG tower detector with hard-negative "
                    "mining, the tower check and the light network with scaled conjugate gradient, "
                    "report held-out accuracy and write the model files.  Photographs come from "
                    "scikit-image's sample data when it is installed (pip install 'rll-bt[vision-train]').")
    t.add_argument("--out", required=True, metavar="DIR", help="directory for the model files and report")
    t.add_argument("--samples", type=_int_at_least(10), default=None, metavar="N",
                   help="rendered training frames (default 1000; --quick: 60)")
    t.add_argument("--seed", type=int, default=0, metavar="S", help="random seed (default 0)")
    t.add_argument("--quick", action="store_true", help="a tiny run (for tests and trying things out)")
    t.add_argument("--members", type=_int_at_least(1), default=None, metavar="K",
                   help="networks per ensemble, for the tower check and the light network "
                        "(default 3; --quick: 2)")
    t.add_argument("--source", choices=sorted(SOURCES), default="world",
                   help="where the frames come from: world (default: the PyBullet world, drawn towers, "
                        "photographs) or raycast (renderer B alone, an evaluation renderer: for the "
                        "benchmark's reverse direction, never for models to ship)")
    t.add_argument("--workers", type=_int_at_least(1), default=min(2, os.cpu_count() or 1), metavar="W",
                   help="worker processes (default: 2 or the number of cores if fewer)")
    t.set_defaults(func=cmd_train_light)

    ph = sub.add_parser(
        "train-physical", help="train the physical tower reader (tag-given regions)",
        description="Render labelled frames (the PyBullet world with training photographs and drawn "
                    "towers, or renderer B alone), describe every candidate box of each tower's "
                    "tag-given region by what a signal tower physically is (per row band: brightness "
                    "against the same box's brightest band, saturation, hue; contrast to the columns "
                    "beside it), train the small network that reads them (8 states or no tower) and "
                    "write it to one file.")
    ph.add_argument("--out", required=True, metavar="FILE", help="model file to write (.npz)")
    ph.add_argument("--frames", type=_int_at_least(10), default=400, metavar="N",
                    help="labelled frames with towers to render (default 400)")
    ph.add_argument("--source", choices=sorted(SOURCES), default="world",
                    help="where the frames come from: world (default) or raycast (renderer B alone: "
                         "the benchmark's reverse direction, never for a model to ship)")
    ph.add_argument("--hidden", type=_int_at_least(2), default=24, metavar="K", help="hidden units (default 24)")
    ph.add_argument("--seed", type=int, default=0, metavar="S", help="random seed (default 0)")
    ph.add_argument("--workers", type=_int_at_least(1), default=min(2, os.cpu_count() or 1), metavar="W",
                    help="worker processes rendering (default: 2 or the number of cores if fewer)")
    ph.set_defaults(func=cmd_train_physical)

    li = sub.add_parser(
        "light", help="find signal towers in images and read their lights",
        description="Find signal towers with the HOG detector and read their light state with the "
                    "network (state: green 1 + yellow 2 + red 4).")
    li.add_argument("images", nargs="+", metavar="IMAGE")
    li.add_argument("--json", action="store_true", help="one JSON object per image and line")
    li.add_argument("--models", metavar="DIR", help="model directory (default: the shipped models)")
    li.add_argument("--region", type=_region, metavar="X,Y,W,H",
                    help="search only this image region (pixels), e.g. where a tag says the tower is")
    li.add_argument("--min-confidence", type=_probability, default=None, metavar="P",
                    help="report a tower only when its most probable state has at least this "
                         "probability (default 0.75; 0 reports every tower found)")
    li.set_defaults(func=cmd_light)

    tg = sub.add_parser(
        "tags", help="find ArUco station tags in images and estimate their poses",
        description="Find DICT_ARUCO_ORIGINAL markers, estimate each one's pose in the camera "
                    "optical frame (x right, y down, z forward; metres) with the profile's tag size, "
                    "and name the machine and side it belongs to.  The camera file is YAML or JSON "
                    "with width, height, fx, fy, cx, cy and optional distortion (OpenCV order).")
    tg.add_argument("images", nargs="+", metavar="IMAGE")
    tg.add_argument("--camera", required=True, metavar="FILE", help="camera intrinsics (YAML or JSON)")
    tg.add_argument("--profile", default=None, metavar="P", help="rules profile (default rcll2016)")
    tg.add_argument("--json", action="store_true", help="one JSON object per image and line")
    tg.add_argument("--all-ids", action="store_true",
                    help="also report markers whose id belongs to no station of the profile")
    tg.set_defaults(func=cmd_tags)


def _probability(text: str) -> float:
    try:
        p = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"not a number: {text!r}") from None
    if not 0.0 <= p <= 1.0:
        raise argparse.ArgumentTypeError(f"must be between 0 and 1, not {p}")
    return p


# -- train-light -------------------------------------------------------------
def cmd_train_light(args) -> int:
    from .light.evaluation import confusion_table
    from .light.training import TrainOptions, train_light
    samples = args.samples if args.samples is not None else (60 if args.quick else 1000)
    members = args.members if args.members is not None else (2 if args.quick else 3)
    opts = TrainOptions(out=args.out, samples=samples, seed=args.seed, quick=args.quick, workers=args.workers,
                        members=members, source=SOURCES[args.source],
                        **({"iterations": 60, "rounds": 1} if args.quick else {}))
    report = train_light(opts, progress=lambda s: print(s, file=sys.stderr, flush=True))
    h = report["heldout"]
    d = report["detector"]
    print(f"models written to {args.out} ({sum(report['files'].values()) / 1024:.0f} KiB) "
          f"in {report['seconds']:.0f} s")
    print(f"held-out: {h['frames']} frames, {h['required_towers']} towers, {h['tower_free_frames']} tower-free")
    print(f"  detector recall        {h['recall']:.4f}")
    print(f"  state accuracy         {h['state_accuracy']:.4f} (of detected towers)")
    print(f"  end to end             {h['end_to_end']:.4f}")
    print(f"  false per 1000 free    {h['false_per_1000']:.1f} "
          f"({h['false_detections_free']} on {h['tower_free_frames']} tower-free frames)")
    print(f"  false per 1000 frames  {h['false_per_1000_all']:.1f} (any frame)")
    print(f"  ms per frame           {h['ms_median']:.1f} median, {h['ms_p95']:.1f} p95")
    print(f"  detector threshold {d['threshold']:.3f}")
    print("confusion (rows: true state, columns: read state):")
    print(confusion_table(h["confusion"]))
    return EXIT_OK


# -- train-physical ----------------------------------------------------------
def cmd_train_physical(args) -> int:
    import time

    import numpy as np

    from .light.physical import samples, train, training_frames
    t0 = time.perf_counter()
    out = os.path.abspath(args.out)
    if not os.path.isdir(os.path.dirname(out)):
        print(f"error: no directory for {args.out}", file=sys.stderr)
        return EXIT_USAGE
    frames = training_frames(SOURCES[args.source], args.frames, args.seed * 1000 + 500_000, args.workers,
                             progress=lambda s: print(s, file=sys.stderr, flush=True))
    try:
        x, y = samples(frames, np.random.default_rng(args.seed))
    except ValueError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return EXIT_FAILURE
    print(f"{len(x)} candidate boxes of {len(frames)} frames; training the network", file=sys.stderr, flush=True)
    reader = train(x, y, hidden=args.hidden, seed=args.seed, trained_on=args.source, frames=len(frames))
    reader.save(out)
    acc = float((reader.probabilities(x).argmax(axis=1) == y).mean())
    print(f"model written to {out} in {time.perf_counter() - t0:.0f} s; "
          f"training accuracy {acc:.4f} on {len(x)} boxes ({int((y < 8).sum())} on towers)")
    return EXIT_OK


# -- light -------------------------------------------------------------------
def _read_image(path: str):
    import cv2
    if not os.path.isfile(path):
        return None, "no such file"
    img = cv2.imread(path, cv2.IMREAD_COLOR)
    if img is None:
        return None, "not an image OpenCV can read"
    return img, None


class _Images:
    """The readable images among ``paths`` as (path, BGR image); unreadable
    ones are reported on stderr and make the exit code 2."""

    def __init__(self, paths: list[str]):
        self.paths = paths
        self.failed = 0

    def __iter__(self):
        for path in self.paths:
            img, why = _read_image(path)
            if img is None:
                print(f"rll-bt: error: {path}: {why}", file=sys.stderr)
                self.failed += 1
                continue
            yield path, img

    @property
    def exit_code(self) -> int:
        return EXIT_USAGE if self.failed else EXIT_OK


def _timed(clock, fn, *args, **kw):
    """(fn's result, milliseconds it took on ``clock``)."""
    t0 = clock.now()
    out = fn(*args, **kw)
    return out, (clock.now() - t0) * 1000.0


def light_json(path: str, ms: float, detections) -> dict:
    """The ``vision light --json`` object of one image."""
    return {"image": path, "ms": round(ms, 3), "detections": [
        {"box": [int(v) for v in d.box], "score": round(float(d.score), 4), "state": int(d.state),
         "lights": {name: "on" if on else "off" for name, on in
                    (("red", d.lights["red"]), ("yellow", d.lights["yellow"]), ("green", d.lights["green"]))},
         "probabilities": [round(float(p), 5) for p in d.probabilities]}
        for d in detections]}


def cmd_light(args) -> int:
    from rll_bt.clock import WallClock

    from .light.reader import LightReader
    reader = LightReader.load(args.models)
    if args.min_confidence is not None:
        reader.min_confidence = args.min_confidence
    clock = WallClock()
    images = _Images(args.images)
    for path, img in images:
        dets, ms = _timed(clock, reader.read, img, region=args.region)
        if args.json:
            print(json.dumps(light_json(path, ms, dets)), flush=True)
        elif not dets:
            print(f"{path}: no signal tower ({ms:.1f} ms)")
        else:
            for d in dets:
                on = "+".join(n for n in ("red", "yellow", "green") if d.lights[n]) or "all off"
                print(f"{path}: tower at {list(d.box)} score {d.score:.2f}: state {d.state} ({on}), "
                      f"p={max(d.probabilities):.3f} ({ms:.1f} ms)")
    return images.exit_code


# -- tags --------------------------------------------------------------------
def cmd_tags(args) -> int:
    import cv2
    import numpy as np

    from rll_bt import rules
    from rll_bt.clock import WallClock
    from rll_bt.errors import UserError

    from .camera_file import load_camera, scaled
    from .tags import TagDetector
    try:
        profile = rules.profile(args.profile)
    except ValueError as exc:
        raise UserError(str(exc)) from None
    camera = load_camera(args.camera)
    detector = TagDetector(profile.tag_size, valid_ids=None if args.all_ids else set(profile.all_tag_ids))
    clock = WallClock()
    images = _Images(args.images)
    for path, img in images:
        dets, ms = _timed(clock, detector.detect, img, scaled(camera, img.shape[1], img.shape[0]))
        tags = []
        for d in dets:
            owner = profile.machine_for_tag(d.tag_id)
            r, _ = cv2.Rodrigues(np.asarray(d.rvec))
            normal = r[:, 2]
            tags.append({
                "id": d.tag_id, "machine": owner[0] if owner else None, "side": owner[1] if owner else None,
                "tvec": [round(v, 4) for v in d.tvec], "rvec": [round(v, 4) for v in d.rvec],
                "distance": round(float(np.linalg.norm(d.tvec)), 4),
                # yaw of the tag face seen from the camera: 0 when it faces the camera squarely
                "yaw_deg": round(math.degrees(math.atan2(-normal[0], -normal[2])), 2),
                "corners": [[round(x, 2), round(y, 2)] for x, y in d.corners]})
        if args.json:
            print(json.dumps({"image": path, "ms": round(ms, 3), "tags": tags}), flush=True)
        elif not tags:
            print(f"{path}: no tag ({ms:.1f} ms)")
        else:
            for t in tags:
                name = f"{t['machine']} {t['side']}" if t["machine"] else "unknown station"
                print(f"{path}: tag {t['id']} ({name}) at {t['distance']:.3f} m, "
                      f"t={t['tvec']}, yaw {t['yaw_deg']:.1f} deg")
    return images.exit_code
