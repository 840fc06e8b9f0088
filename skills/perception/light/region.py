"""Where the signal tower must be in the image, from a tag on the same station.

The tag's pose in the camera frame (solvePnP) fixes the station: the tower
stands at ``(tower_x, tower_y)`` of the machine frame from
``tower_base`` up ``tower_height`` (:mod:`rll_bt.rules.geometry`), and the
tag is centred under the belt on the input (+x) or output (-x) face.  The
tower's cylinder is projected into the image through the tag pose (with the
camera's distortion) and widened by a margin for the tag pose's error and
for towers mounted a little differently from the rules' drawing.
"""
from __future__ import annotations

import math

import cv2
import numpy as np

from rll_bt.backend import CameraIntrinsics, TagDetection
from rll_bt.rules import MpsGeometry


def tower_points_in_tag_frame(side: str, mps: MpsGeometry, ring: int = 8) -> np.ndarray:
    """Points on the tower's bottom and top rims in the frame of the tag on
    ``side`` ("INPUT"/"OUTPUT"): x to the marker's right, y up, z out of the face."""
    if side not in ("INPUT", "OUTPUT"):
        raise ValueError(f"side must be INPUT or OUTPUT, not {side!r}")
    sign = 1.0 if side == "INPUT" else -1.0
    tag = np.array([sign * mps.depth / 2.0, mps.belt_offset_y, mps.tag_centre_height])
    pts = []
    for z in (mps.tower_base, mps.tower_base + mps.tower_height):
        for a in np.linspace(0.0, 2.0 * math.pi, ring, endpoint=False):
            d = np.array([mps.tower_x + mps.tower_radius * math.cos(a),
                          mps.tower_y + mps.tower_radius * math.sin(a), z]) - tag
            # machine -> tag axes: input face x_tag = +y, z_tag = +x; output face x_tag = -y, z_tag = -x
            pts.append((sign * d[1], d[2], sign * d[0]))
    return np.asarray(pts, np.float64)


def tower_region(det: TagDetection, side: str, mps: MpsGeometry, intrinsics: CameraIntrinsics,
                 margin_x: float = 1.5, margin_y: float = 0.5, min_size: int = 24
                 ) -> tuple[tuple[int, int, int, int], float] | None:
    """((x, y, w, h) image region to search, expected tower height in pixels),
    or None when the tower would be behind the camera or outside the image,
    or the tag's pose or the projection is not finite.

    The projected tower box is widened by ``margin_x`` tower widths on each
    side and ``margin_y`` tower heights above and below: room for the tag
    pose's error and for the detector's window, which needs background
    around the tower."""
    pts = tower_points_in_tag_frame(side, mps)
    rvec = np.asarray(det.rvec, np.float64).reshape(3, 1)
    tvec = np.asarray(det.tvec, np.float64).reshape(3, 1)
    if not (np.all(np.isfinite(rvec)) and np.all(np.isfinite(tvec))):
        return None
    r, _ = cv2.Rodrigues(rvec)
    if np.any((r @ pts.T + tvec)[2] <= 0.05):
        return None
    uv, _ = cv2.projectPoints(pts, rvec, tvec, intrinsics.matrix, np.asarray(intrinsics.distortion, np.float64))
    uv = uv.reshape(-1, 2)
    if not np.all(np.isfinite(uv)):     # the lens model diverges far outside the image
        return None
    x0, y0 = uv.min(axis=0)
    x1, y1 = uv.max(axis=0)
    w, h = x1 - x0, y1 - y0
    mx = max(margin_x * w, min_size / 2)
    my = max(margin_y * h, min_size / 2)
    rx0, ry0 = max(0, int(math.floor(x0 - mx))), max(0, int(math.floor(y0 - my)))
    rx1 = min(intrinsics.width, int(math.ceil(x1 + mx)))
    ry1 = min(intrinsics.height, int(math.ceil(y1 + my)))
    if rx1 - rx0 < 4 or ry1 - ry0 < 4:
        return None
    return (rx0, ry0, rx1 - rx0, ry1 - ry0), float(h)
