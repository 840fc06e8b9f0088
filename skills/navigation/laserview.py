"""What the laser sees, made usable while the robot moves and where it is blind.

- :class:`OdometryHistory`: recent odometry poses, so a scan taken a little
  earlier (lasers run at 10-15 Hz) is moved into the robot frame of *now*
  before it is checked against the direction of travel.
- :class:`LaserMemory`: unexplained laser points (not walls or known
  stations: other robots, stations not yet in the map) kept for a few
  seconds in the field frame, so a motion into the laser's blind sector
  (behind the robot) is still checked against what was seen there.
"""
from __future__ import annotations

from collections import deque

import numpy as np

from rll_bt.backend import Pose2D

from .safety import to_field


class OdometryHistory:
    def __init__(self, span: float = 1.0):
        self.span = span
        self._items: deque[tuple[float, Pose2D]] = deque()

    def add(self, stamp: float, pose: Pose2D) -> None:
        if self._items and self._items[-1][0] == stamp:
            return
        self._items.append((stamp, pose))
        while self._items and self._items[0][0] < stamp - self.span:
            self._items.popleft()

    def at(self, stamp: float) -> Pose2D | None:
        """The recorded pose nearest in time to ``stamp`` (None when empty)."""
        if not self._items:
            return None
        return min(self._items, key=lambda item: abs(item[0] - stamp))[1]

    def interpolate(self, stamp: float) -> Pose2D | None:
        """The pose at ``stamp``, linear between the two recorded poses around
        it (a recorded pose itself at its own stamp); None when ``stamp`` lies
        outside the recorded span."""
        items = self._items
        if not items or stamp < items[0][0] or stamp > items[-1][0]:
            return None
        for (t0, p0), (t1, p1) in zip(items, list(items)[1:]):
            if t0 <= stamp <= t1:
                if stamp == t1:
                    return p1
                f = (stamp - t0) / (t1 - t0)
                step = p1.relative_to(p0)
                return p0.compose(Pose2D(step.x * f, step.y * f, step.theta * f))
        return items[0][1]


def points_now(points_then: np.ndarray, odom_then: Pose2D, odom_now: Pose2D) -> np.ndarray:
    """Points (K, 2) in the robot frame of a scan taken at ``odom_then``,
    expressed in the robot frame at ``odom_now``."""
    moved = odom_now.relative_to(odom_then)
    back = moved.inverse()
    return to_field(points_then, back)


class LaserMemory:
    """Field-frame points, each forgotten after ``ttl`` seconds, thinned to
    one per ``cell`` metres.  A scan that covers a remembered point (``view``
    of :meth:`add`) replaces it: the scan's own points are what is there now,
    so the memory keeps, for longer, only what lies where the laser cannot
    see at the moment (behind the robot)."""

    def __init__(self, ttl: float = 30.0, cell: float = 0.05, radius: float = 2.5):
        self.ttl, self.cell, self.radius = ttl, cell, radius
        self.points = np.zeros((0, 2))
        self.expiry = np.zeros(0)

    def add(self, points: np.ndarray, now: float, centre: tuple[float, float],
            view: tuple[float, float, float, float, float] | None = None) -> None:
        """Remember ``points`` (field frame) seen at ``now`` by a robot at
        ``centre``; ``view`` = (x, y, heading, half angle, range) of the laser
        that saw them, in the field frame: older points inside it are dropped."""
        keep = self.expiry > now
        if view is not None and keep.any():
            x, y, heading, half, reach = view
            dx, dy = self.points[:, 0] - x, self.points[:, 1] - y
            bearing = np.arctan2(dy, dx) - heading
            inside = (np.abs((bearing + np.pi) % (2.0 * np.pi) - np.pi) < half) & (np.hypot(dx, dy) < reach)
            keep &= ~inside
        pts = np.concatenate([self.points[keep], points])
        exp = np.concatenate([self.expiry[keep], np.full(len(points), now + self.ttl)])
        near = np.hypot(pts[:, 0] - centre[0], pts[:, 1] - centre[1]) <= self.radius
        pts, exp = pts[near], exp[near]
        if len(pts):
            keys = np.floor(pts / self.cell).astype(np.int64)
            # the newest sighting of each cell wins (later rows come last)
            _, idx = np.unique(keys[::-1], axis=0, return_index=True)
            idx = len(pts) - 1 - idx
            pts, exp = pts[idx], exp[idx]
        self.points, self.expiry = pts, exp

    def relative(self, pose: Pose2D, now: float) -> np.ndarray:
        """Remembered points relative to ``pose`` (field-frame axes)."""
        live = self.expiry > now
        return self.points[live] - np.array([pose.x, pose.y])


def laser_view(ctx, pose: Pose2D, reach: float, inset: float = 0.1) -> tuple[float, float, float, float, float]:
    """The laser's view for :meth:`LaserMemory.add`: (x, y, heading, half
    angle, range) in the field frame for a robot at ``pose``, the angle
    ``inset`` radians inside the edge of the field of view."""
    mx, my, _ = ctx.robot.laser_mount
    c, s = np.cos(pose.theta), np.sin(pose.theta)
    return (pose.x + c * mx - s * my, pose.y + s * mx + c * my, pose.theta,
            ctx.robot.laser_fov / 2.0 - inset, reach)
