"""Stopping for what the laser sees (stations, walls, other robots).

The check looks along the commanded direction of travel: a laser point
ahead (within the robot's width plus ``lateral_margin``) limits the speed
to what still stops ``margin`` metres before it with ``decel``; closer
than that the robot is *blocked*.  Points the map does not explain may be
other robots: for them the margins are larger and the stopping distance
allows for their own approach (``closing``).
"""
from __future__ import annotations

import math

import numpy as np

from rll_bt.backend import LaserScan, Pose2D


def scan_points(scan: LaserScan, max_range: float | None = None) -> np.ndarray:
    """Valid returns (K, 2) in the robot frame."""
    r = np.asarray(scan.ranges, dtype=float)
    ok = np.isfinite(r) & (r >= scan.range_min) & (r < scan.range_max)
    if max_range is not None:
        ok &= r <= max_range
    a = scan.angles[ok] + scan.mount.theta
    return np.column_stack([scan.mount.x + r[ok] * np.cos(a), scan.mount.y + r[ok] * np.sin(a)])


def to_field(points: np.ndarray, pose: Pose2D) -> np.ndarray:
    c, s = math.cos(pose.theta), math.sin(pose.theta)
    return np.column_stack([pose.x + c * points[:, 0] - s * points[:, 1],
                            pose.y + s * points[:, 0] + c * points[:, 1]])


def _project(points: np.ndarray, vx: float, vy: float) -> tuple[np.ndarray, np.ndarray] | None:
    """(along, |lateral|) of the points relative to the direction (vx, vy),
    or None without motion or points."""
    speed = math.hypot(vx, vy)
    if speed < 1e-6 or len(points) == 0:
        return None
    ux, uy = vx / speed, vy / speed
    return points[:, 0] * ux + points[:, 1] * uy, np.abs(points[:, 1] * ux - points[:, 0] * uy)


def clear_distance(points: np.ndarray, vx: float, vy: float, radius: float,
                   lateral_margin: float) -> float:
    """Free distance (m) the robot's disc can travel along (vx, vy) before
    touching a point, ``inf`` when nothing is in the way."""
    proj = _project(points, vx, vy)
    if proj is None:
        return math.inf
    along, lateral = proj
    width = radius + lateral_margin
    hit = (along > 0.0) & (lateral < width)
    if not hit.any():
        return math.inf
    # distance until the disc's front meets the point
    front = along[hit] - np.sqrt(np.maximum(width * width - lateral[hit] ** 2, 0.0))
    return float(max(front.min(), 0.0))


def free_distance(points: np.ndarray, vx: float, vy: float, radius: float, margin: float,
                  lateral_margin: float, hard: float = 0.02) -> float:
    """Distance (m) the robot may still travel along (vx, vy) keeping
    ``margin`` ahead of every point and ``lateral_margin`` beside it.

    A point already inside that band is different: ahead of the robot it
    blocks only when the bare disc (plus ``hard``) would run into it;
    beside or behind it does not block a motion that does not approach it
    (the robot may pass a station at a few centimetres, never into it)."""
    proj = _project(points, vx, vy)
    if proj is None:
        return math.inf
    along, lateral = proj
    width = radius + lateral_margin
    band = lateral < width
    if not band.any():
        return math.inf
    along, lateral = along[band], lateral[band]
    t = along - np.sqrt(np.maximum(width * width - lateral * lateral, 0.0))
    ahead = t > 0.0
    free = math.inf
    if ahead.any():
        free = float(max(t[ahead].min() - margin, 0.0))
    inside = ~ahead & (along > 0.0) & (lateral < radius + hard)
    if inside.any():
        free = 0.0
    return free


def speed_limit(points: np.ndarray, vx: float, vy: float, radius: float, margin: float,
                lateral_margin: float, decel: float, latency: float = 0.0, closing: float = 0.0) -> float:
    """Highest speed v (m/s) along (vx, vy) that still stops ``margin``
    before the nearest point ahead, braking at ``decel`` after ``latency``
    seconds, while the point itself may come closer at ``closing`` m/s
    until the robot stands (another robot braking too):
    v * latency + v^2 / (2 decel) + closing * (latency + v / decel) <= free.
    0 means blocked.  The free distance is :func:`free_distance`."""
    free = free_distance(points, vx, vy, radius, margin, lateral_margin)
    if math.isinf(free):
        return math.inf
    b = latency + closing / decel
    c = closing * latency - free
    if c >= 0.0:
        return 0.0
    return decel * (-b + math.sqrt(b * b - 2.0 * c / decel))


def radial_limit(points: np.ndarray, ux: float, uy: float, radius: float, margin: float, decel: float,
                 latency: float, closing: float, near: float) -> float:
    """Highest speed (m/s) along the unit direction (ux, uy) whose part
    toward each point (robot-centred, field axes) within ``near`` of the
    robot's disc still stops ``margin`` short of it (braking at ``decel``
    after ``latency``) while the point comes on at ``closing`` m/s: the
    limit of :func:`speed_limit` along the line to the point, divided by how
    much of the motion goes that way.  0 means blocked; ``inf`` when no point
    near lies ahead of the robot's side."""
    if len(points) == 0:
        return math.inf
    d = np.hypot(points[:, 0], points[:, 1])
    ok = d > 1e-6
    toward = np.zeros(len(points))
    toward[ok] = (points[ok, 0] * ux + points[ok, 1] * uy) / d[ok]
    sel = ok & (d - radius < near) & (toward > 0.05)
    if not sel.any():
        return math.inf
    free = d[sel] - radius - margin
    b = latency + closing / decel
    c = closing * latency - free
    vr = np.where(c >= 0.0, 0.0, decel * (-b + np.sqrt(np.maximum(b * b - 2.0 * c / decel, 0.0))))
    return float((vr / toward[sel]).min())


#: s a poll may come later than the control period before it counts as a longer reaction time
LATE = 0.02


def poll_lag(lag: float, dt: float, period: float) -> float:
    """The seconds between a motion's polls, the worst lately: ``lag`` after a poll
    ``dt`` after the one before (a gap over 0.5 s counts as 0.5 s, the base's deadman;
    never under the control ``period``)."""
    return max(min(dt, 0.5), lag * 0.97, period)
