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


def points_now(points_then: np.ndarray, odom_then: Pose2D, odom_now: Pose2D) -> np.ndarray:
    """Points (K, 2) in the robot frame of a scan taken at ``odom_then``,
    expressed in the robot frame at ``odom_now``."""
    moved = odom_now.relative_to(odom_then)
    back = moved.inverse()
    return to_field(points_then, back)


class LaserMemory:
    """Field-frame points, each forgotten after ``ttl`` seconds, thinned to
    one per ``cell`` metres."""

    def __init__(self, ttl: float = 10.0, cell: float = 0.05, radius: float = 2.5):
        self.ttl, self.cell, self.radius = ttl, cell, radius
        self.points = np.zeros((0, 2))
        self.expiry = np.zeros(0)

    def add(self, points: np.ndarray, now: float, centre: tuple[float, float]) -> None:
        keep = self.expiry > now
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
