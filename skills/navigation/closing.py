"""Other robots that come closer from the side.

The laser check of :mod:`.safety` looks along the robot's own way: a robot
whose way converges with another's at a shallow angle has the other always
beside its way, never in it, until the two touch side to side (two teams'
robots, each driving at 0.6 m/s, in the 2025 head-to-head game of seed 3).
:class:`ClosingWatch` keeps the last second of laser points the map does not
explain and measures how fast the nearest of them comes toward where the
robot is now (the robot's own motion does not count).  Other robots are discs
of the robot's own radius: the point of one nearest the laser lies on the line
to its centre, so the centre found from it does not move as the view changes
(driving past a parked robot shows it from another side).  While something has
been coming closer lately, :func:`~.safety.radial_limit` bounds the robot's
own speed toward every such point near it, so that it could still stop
short of it with the other coming on.  A robot standing still beside the way
never starts it (a parked robot, a robot at a station).
"""
from __future__ import annotations

from collections import deque

import numpy as np

from .yielding import disc_centre

#: m/s toward the robot above which the nearest unexplained point counts as coming closer
COMING = 0.08
#: s the watch stays on after the last time something came closer (both robots stopped:
#: neither drives on into the other the moment the closing stops)
HOLD = 2.0
#: s back in time the closing is measured over (at least, at most)
SPAN = (0.3, 0.8)
#: m: the points of an earlier scan that belong to the same thing as the nearest one now
SAME = 0.6
#: m beyond the robot's radius within which points are watched
NEAR = 1.0


class ClosingWatch:
    def __init__(self):
        self.scans: deque[tuple[float, np.ndarray, np.ndarray]] = deque()    # (time, points, robot position)
        self.closing = 0.0          # m/s, the nearest unexplained point's speed toward the robot
        self.hot_until = -np.inf

    def update(self, points: np.ndarray, here: np.ndarray, now: float, radius: float) -> None:
        """``points``: this scan's unexplained points (field frame); ``here``: the robot's position."""
        near = points[np.hypot(*(points - here).T) < radius + NEAR] if len(points) else points
        self.closing = self._closing(near, here, now, radius)
        if self.closing > COMING:
            self.hot_until = now + HOLD
        self.scans.append((now, near, here.copy()))
        while self.scans and now - self.scans[0][0] > SPAN[1]:
            self.scans.popleft()

    def _closing(self, near: np.ndarray, here: np.ndarray, now: float, radius: float) -> float:
        if not len(near):
            return 0.0
        then = [scan for scan in self.scans if SPAN[0] <= now - scan[0] <= SPAN[1]]
        if not then:
            return 0.0
        t, old, there = then[0]
        now_disc = disc_centre(near, here, radius)
        if now_disc is None:
            return 0.0
        centre = now_disc[0]
        same = old[np.hypot(*(old - centre).T) < SAME] if len(old) else old
        before = disc_centre(same, there, radius)
        if before is None:
            return 0.0
        return float((np.hypot(*(before[0] - here)) - np.hypot(*(centre - here))) / (now - t))

    def active(self, now: float) -> bool:
        return now < self.hot_until

