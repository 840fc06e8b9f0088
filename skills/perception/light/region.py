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


def tower_box(det: TagDetection, side: str, mps: MpsGeometry, intrinsics: CameraIntrinsics
              ) -> tuple[float, float, float, float] | None:
    """The tower's outline (x0, y0, x1, y1) in the image, as the tag's pose
    projects it (not clipped to the image), or None when the tower would be
    behind the camera or the tag's pose or the projection is not finite."""
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
    return float(x0), float(y0), float(x1), float(y1)


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
    box = tower_box(det, side, mps, intrinsics)
    if box is None:
        return None
    x0, y0, x1, y1 = box
    w, h = x1 - x0, y1 - y0
    mx = max(margin_x * w, min_size / 2)
    my = max(margin_y * h, min_size / 2)
    rx0, ry0 = max(0, int(math.floor(x0 - mx))), max(0, int(math.floor(y0 - my)))
    rx1 = min(intrinsics.width, int(math.ceil(x1 + mx)))
    ry1 = min(intrinsics.height, int(math.ceil(y1 + my)))
    if rx1 - rx0 < 4 or ry1 - ry0 < 4:
        return None
    return (rx0, ry0, rx1 - rx0, ry1 - ry0), float(h)


def tower_readable(det: TagDetection, side: str, mps: MpsGeometry, intrinsics: CameraIntrinsics,
                   camera_height: float, min_visible: float = 0.15, border: float = 1.0) -> bool:
    """May the tower the tag ``det`` places be read from this camera?  Only
    when all of it is in the image (``border`` pixels in from its edges) and
    the camera, ``camera_height`` above the floor, sees at least
    ``min_visible`` of its lowest lamp over the station
    (:func:`lowest_lamp_visible`).  A tower cut by the image's edge or hidden
    in part by its station is read as if the lamps out of sight were unlit,
    and sure of it: in the rendered games a cap station's tower read from
    its input side gave green, yellow and red as yellow and red (0.999) and
    green alone as all dark (0.99)."""
    box = tower_box(det, side, mps, intrinsics)
    if box is None:
        return False
    x0, y0, x1, y1 = box
    if x0 < border or y0 < border or x1 > intrinsics.width - border or y1 > intrinsics.height - border:
        return False
    cam = camera_in_machine_frame(det, side, mps)
    if cam is None:
        return False
    cam[2] = camera_height               # known better than the tag's pose tells it
    return lowest_lamp_visible(cam, mps) >= min_visible


def camera_in_machine_frame(det: TagDetection, side: str, mps: MpsGeometry) -> np.ndarray | None:
    """The camera's position (x, y, z) in the frame of the station whose tag on
    ``side`` is ``det`` (the inverse of :func:`tower_points_in_tag_frame`'s
    axes), or None when the tag's pose is not finite."""
    if side not in ("INPUT", "OUTPUT"):
        raise ValueError(f"side must be INPUT or OUTPUT, not {side!r}")
    rvec = np.asarray(det.rvec, np.float64).reshape(3, 1)
    tvec = np.asarray(det.tvec, np.float64).reshape(3)
    if not (np.all(np.isfinite(rvec)) and np.all(np.isfinite(tvec))):
        return None
    r, _ = cv2.Rodrigues(rvec)
    c = -r.T @ tvec                      # the camera in the tag's axes
    sign = 1.0 if side == "INPUT" else -1.0
    return np.array([sign * mps.depth / 2.0 + sign * c[2], mps.belt_offset_y + sign * c[0],
                     mps.tag_centre_height + c[1]])


def lowest_lamp_visible(camera: tuple[float, float, float] | np.ndarray, mps: MpsGeometry) -> float:
    """Which share (0..1) of the tower's lowest lamp (green) a camera at
    ``camera`` (x, y, z in the machine frame) sees over the station.

    The rules draw the cabinet up to ``mps.height``, the tower's base, and
    what stands on it (belt, the cap station's shelf, the ring station's
    slide) below that: a camera lower than the top sees the tower's foot
    only over the cabinet's edge nearest to it.  The sight line to each
    height of the lamp's front (the tower's side facing the camera) enters
    the footprint somewhere on its edge; the lamp is seen at heights whose
    line is at or above ``mps.height`` there.  A camera far off in front of
    the output face (the tower stands near it) sees most of the lamp, one at
    the input face, across the belt, little or none of it."""
    cx, cy, cz = (float(v) for v in camera)
    tx, ty = mps.tower_x, mps.tower_y
    dx, dy = cx - tx, cy - ty
    r = math.hypot(dx, dy)
    if r <= mps.tower_radius:
        return 0.0
    px, py = tx + mps.tower_radius * dx / r, ty + mps.tower_radius * dy / r   # the front of the tower
    lo = mps.tower_base + mps.tower_segment_border
    hi = mps.tower_base + mps.tower_segment
    if cz >= mps.height:
        return 1.0
    # where the horizontal line camera -> front leaves the footprint, as a share s of the way
    # from the front to the camera (0: at the front); the line is at height
    # z + (cz - z) * s there, which must be >= height
    hx, hy = mps.depth / 2.0, mps.width / 2.0
    s_exit = 1.0
    for p, d, h in ((px, cx - px, hx), (py, cy - py, hy)):
        if abs(d) > 1e-12:
            s_exit = min(s_exit, (math.copysign(h, d) - p) / d)
    s_exit = max(0.0, s_exit)
    if s_exit >= 1.0:                    # the camera stands over the footprint
        return 1.0
    # z + (cz - z) * s >= H  <=>  z >= (H - cz * s) / (1 - s)
    z_min = (mps.height - cz * s_exit) / (1.0 - s_exit)
    return float(np.clip((hi - z_min) / (hi - lo), 0.0, 1.0))
