"""A laser and bumper check for the short motions near stations that do
not plan (lining up on a tag, sliding along a face, backing off).

:class:`MotionGuard` answers how fast the robot may move in a direction of
its own frame: the latest scan's points (moved to now by odometry) ahead
within the robot's width plus ``lateral`` must stay ``margin`` metres
away (points the map does not explain, other robots, ``OTHER_MARGIN`` and
``OTHER_LATERAL`` more), braking at the base's deceleration; toward where the laser is blind
(behind) the unexplained points remembered by navigation
(``ctx.laser_memory``: other robots seen on the way in) count instead.  A
pressed bumper stops every motion but one away from what it touches (:meth:`MotionGuard.touching`:
the map's walls and stations near the robot's outline, and the laser's points), at
``BUMPED_SPEED``; with nothing of the kind near, it stops every motion.  Units: metres, seconds, the robot
frame (x forward, y left).
"""
from __future__ import annotations

import math

import numpy as np

from rll_bt.backend import CapabilityError

from ..errors import NotLocalised
from .laserview import laser_view, points_now
from .others import unexplained
from .safety import LATE, scan_points, speed_limit, to_field

#: more room (m) kept from what the map does not explain (other robots): ahead and beside
OTHER_MARGIN = 0.07
OTHER_LATERAL = 0.04
#: m beyond the robot's radius within which the map's walls and stations (from the believed pose,
#: a few centimetres off) and the laser's points may be what a pressed bumper touches
TOUCH_BAND = 0.12
#: m/s; the most a robot whose bumper is pressed moves away from what it touches
BUMPED_SPEED = 0.05


class MotionGuard:
    def __init__(self, ctx, margin: float = 0.03, lateral: float = 0.02, max_range: float = 1.5):
        self.ctx = ctx
        self.margin = margin
        self.lateral = lateral
        self.max_range = max_range
        self.reason = ""
        self._no_laser = False
        self._no_bumper = False

    def _points(self) -> tuple[np.ndarray, np.ndarray]:
        """Laser points in the robot frame of now: (walls and stations of the
        map, the rest: other robots, mostly), both empty without a laser.
        The rest goes into ``ctx.laser_memory`` (what stood beside the robot
        while it lined up is still known when it backs off, blind)."""
        none = np.zeros((0, 2))
        if self._no_laser:
            return none, none
        ctx = self.ctx
        try:
            scan = ctx.backend.laser_scan()
        except CapabilityError:
            self._no_laser = True
            return none, none
        if scan is None:
            return none, none
        pts = scan_points(scan, max_range=self.max_range)
        then = ctx.odometry_history.at(scan.stamp)
        if then is not None:
            pts = points_now(pts, then, ctx.backend.odometry().pose)
        try:
            pose = ctx.pose()
        except NotLocalised:
            return pts, none
        field = to_field(pts, pose)
        other = unexplained(ctx, field)
        now = ctx.clock.now()
        ctx.laser_memory.add(field[other], now, (pose.x, pose.y), laser_view(ctx, pose, self.max_range))
        return pts[~other], pts[other]

    def see(self) -> None:
        """Put what the latest scan shows of other robots into ``ctx.laser_memory``
        (without moving: a turn that looks round before a blind move)."""
        self._points()

    def _remembered(self) -> np.ndarray:
        """Remembered unexplained points in the robot frame."""
        ctx = self.ctx
        try:
            pose = ctx.pose()
        except NotLocalised:
            return np.zeros((0, 2))
        rel = ctx.laser_memory.relative(pose, ctx.clock.now())
        c, s = math.cos(-pose.theta), math.sin(-pose.theta)
        return np.column_stack([c * rel[:, 0] - s * rel[:, 1], s * rel[:, 0] + c * rel[:, 1]])

    def bumped(self) -> bool:
        if self._no_bumper:
            return False
        try:
            return bool(self.ctx.backend.bumper())
        except CapabilityError:
            self._no_bumper = True
            return False

    def limit(self, vx: float, vy: float, lag: float | None = None) -> float:
        """Highest speed (m/s) allowed along the robot-frame direction
        (vx, vy); 0 means blocked (``reason`` says by what).  ``lag``: the
        seconds between the caller's polls lately (a loaded machine polls
        late); more than ``LATE`` over the control period counts as the
        reaction time, and another robot may come that much closer."""
        speed = math.hypot(vx, vy)
        if speed < 1e-9:
            return math.inf
        ux, uy = vx / speed, vy / speed
        top = math.inf
        if self.bumped():
            toward = self.touching()
            if not len(toward) or float((toward @ np.array([ux, uy])).max()) > 0.0:
                self.reason = "the bumper is pressed"
                return 0.0
            top = BUMPED_SPEED        # away from all it may touch: slowly
        r = self.ctx.robot
        decel = self.ctx.settings.max_decel * 0.8
        s = self.ctx.settings
        period = s.control_period
        side = self.lateral + OTHER_LATERAL
        if lag is not None and lag - period > LATE:
            side += s.closing_speed * (lag - period)
            period = lag
        blind = abs(math.atan2(uy, ux)) > r.laser_fov / 2.0 - 0.4
        fixed, other = (np.zeros((0, 2)), self._remembered()) if blind else self._points()
        # stations and walls at a few centimetres; other robots with the navigation's wider berth
        cap = min(speed_limit(fixed, ux, uy, r.radius, self.margin, self.lateral, decel, period),
                  speed_limit(other, ux, uy, r.radius, self.margin + OTHER_MARGIN, side, decel, period))
        if cap <= 0.0:
            self.reason = "something is in the way" + (" (seen earlier, behind the robot)" if blind else "")
        return min(cap, top)

    def touching(self) -> np.ndarray:
        """Unit vectors (robot frame) toward what a pressed bumper may be touching: the
        nearest point of every wall and station edge of the map within ``TOUCH_BAND`` of the
        robot's outline (from the believed pose), and the laser's points that near.  Empty
        when nothing is (another robot behind, unseen) or the pose is not known: then no
        direction is known to be away from it."""
        r = self.ctx.robot.radius
        fixed, other = self._points()
        pts = np.concatenate([fixed, other], axis=0)
        near = pts[np.hypot(pts[:, 0], pts[:, 1]) <= r + TOUCH_BAND] if len(pts) else pts
        try:
            pose = self.ctx.pose()
        except NotLocalised:
            pose = None
        if pose is not None:
            segs = self.ctx.map.segments()
            a, ab = segs[:, :2], segs[:, 2:] - segs[:, :2]
            q = np.array([pose.x, pose.y]) - a
            t = np.clip((q * ab).sum(axis=1) / np.maximum((ab * ab).sum(axis=1), 1e-12), 0.0, 1.0)
            closest = a + t[:, None] * ab
            d = np.hypot(closest[:, 0] - pose.x, closest[:, 1] - pose.y)
            rel = closest[d <= r + TOUCH_BAND] - np.array([pose.x, pose.y])
            c, s = math.cos(-pose.theta), math.sin(-pose.theta)
            near = np.concatenate([near, np.column_stack([c * rel[:, 0] - s * rel[:, 1],
                                                          s * rel[:, 0] + c * rel[:, 1]])], axis=0)
        n = np.hypot(near[:, 0], near[:, 1])
        return near[n > 1e-9] / n[n > 1e-9, None]

    def clamp(self, vx: float, vy: float, lag: float | None = None) -> tuple[float, float]:
        """(vx, vy) slowed to :meth:`limit` along its direction."""
        speed = math.hypot(vx, vy)
        cap = self.limit(vx, vy, lag)
        if speed <= cap:
            return vx, vy
        k = max(cap, 0.0) / speed
        return vx * k, vy * k

