"""Camera calibration files for the vision commands.

A YAML or JSON mapping (the same keys either way)::

    width: 640            # image size the calibration is for, pixels
    height: 480
    fx: 531.2             # focal lengths, pixels
    fy: 531.2
    cx: 320.0             # principal point, pixels
    cy: 240.0
    distortion: [0.0, 0.0, 0.0, 0.0, 0.0]   # optional: OpenCV's k1 k2 p1 p2 [k3 ...]

Images of another size are used with the intrinsics scaled to their size
(same field of view), since a camera driver may deliver a scaled image.
"""
from __future__ import annotations

import json
import math
from pathlib import Path

import yaml

from rll_bt.backend import CameraIntrinsics
from rll_bt.errors import UserError

REQUIRED = ("width", "height", "fx", "fy", "cx", "cy")


def load_camera(path: str | Path) -> CameraIntrinsics:
    """Read a camera file; a clear :class:`UserError` names what is wrong."""
    p = Path(path)
    try:
        text = p.read_text(encoding="utf-8")
    except OSError as exc:
        raise UserError(f"cannot read the camera file: {exc.strerror or exc}", where=str(p)) from None
    try:
        data = json.loads(text) if p.suffix.lower() == ".json" else yaml.safe_load(text)
    except (json.JSONDecodeError, yaml.YAMLError) as exc:
        raise UserError(f"not valid {'JSON' if p.suffix.lower() == '.json' else 'YAML'}: {exc}", where=str(p)) from None
    if not isinstance(data, dict):
        raise UserError("a camera file is a mapping with width, height, fx, fy, cx, cy (and distortion)",
                        where=str(p))
    missing = [k for k in REQUIRED if k not in data]
    if missing:
        raise UserError(f"missing key(s): {', '.join(missing)}", where=str(p),
                        hint="keys: width, height, fx, fy, cx, cy, optional distortion")
    values = {}
    for k in REQUIRED:
        v = data[k]
        if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v) or v <= 0:
            raise UserError(f"{k} must be a positive number, not {v!r}", where=str(p))
        values[k] = v
    dist = data.get("distortion", [0.0] * 5) or []
    if not isinstance(dist, list) or len(dist) not in (4, 5, 8, 12, 14) or \
            not all(isinstance(d, (int, float)) and not isinstance(d, bool) for d in dist):
        raise UserError("distortion must be a list of 4, 5, 8, 12 or 14 numbers (OpenCV order)", where=str(p))
    return CameraIntrinsics(int(values["width"]), int(values["height"]), float(values["fx"]),
                            float(values["fy"]), float(values["cx"]), float(values["cy"]),
                            tuple(float(d) for d in dist) or (0.0,) * 5)


def scaled(intr: CameraIntrinsics, width: int, height: int) -> CameraIntrinsics:
    """The intrinsics for an image of ``width`` x ``height`` from the same camera."""
    if (width, height) == (intr.width, intr.height):
        return intr
    sx, sy = width / intr.width, height / intr.height
    return CameraIntrinsics(width, height, intr.fx * sx, intr.fy * sy, intr.cx * sx, intr.cy * sy,
                            intr.distortion)
