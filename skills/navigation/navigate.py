"""Driving to a goal: plan on the costmap, follow the path, stop for what
the laser sees, replan around it, give up after a timeout.

:class:`Navigate` is a non-blocking activity.  Each poll reads the pose
and the latest scan, commands one velocity and returns.  When the laser
check holds the robot still for ``block_replan_after`` seconds, the
unexplained laser points near the robot (not walls or known stations:
other robots, unknown stations) go into the costmap for
``obstacle_ttl`` seconds and the path is replanned; while no path exists
the robot waits, and after ``max_blocked`` seconds it fails with
``NAVIGATION_FAILED``.  Other robots (:mod:`.others`): a robot at a station
keeps the strip behind it that it backs off into, and the robot waits
``GOAL_WAIT`` metres before a goal another robot stands on until it is free.  A navigation
looks before it leaves: it turns toward its way out before it drives
(:class:`~.controller.PathFollower`'s ``look_angle``).  A navigation that finds no path at its start
clears those remembered obstacles (they were seen on an earlier way) and
plans again before it gives up.  A robot that does not move (by odometry) although
commanded counts as blocked too (something the laser does not see).  Time blocked by
another robot does not count toward the time limit taken from the distance.  Blocked
by another robot with no way round it, a navigation steps aside for a while
(:mod:`.yielding`: two robots each in the other's only way would otherwise wait
for each other until both fail, again and again).  A robot coming closer from the side
(:mod:`.closing`) bounds the speed toward it, not only along the way.  Losing localisation fails with
``LOCALISATION_LOST``; the time limit with ``TIMEOUT``.
"""
from __future__ import annotations

import logging
import math

import numpy as np

from rll_bt.backend import CapabilityError, Pose2D, wrap_angle

from ..activity import Activity, Status
from ..errors import SkillError, SkillFailure
from .closing import ClosingWatch
from .controller import Limits, PathFollower
from .goals import nearest_fit, standing_clearance
from .laserview import laser_view, points_now
from .others import occupied, station_zones, unexplained
from .planner import GridPlanner, NoPath
from .safety import LATE, clear_distance, poll_lag, radial_limit, scan_points, speed_limit, to_field
from .yielding import PATIENT, blocker, yield_delay, yield_spot

log = logging.getLogger(__name__)

#: metres from a goal another robot takes up (or backs off over) where the robot waits for it
GOAL_WAIT = 1.0
#: room (m) beyond the robot's radius a goal needs free of other robots
GOAL_ROOM = 0.1
#: m beyond the robot's disc within which a robot coming closer from the side limits the speed toward it
RADIAL_NEAR = 0.6


def tight_speed(gap, settings) -> np.ndarray:
    """Top speed (m/s) where the robot passes a wall or station ``gap``
    metres away: ``tight_min_speed`` at the planner's padding, rising by
    ``tight_slope`` m/s per metre of more room."""
    g = np.asarray(gap, dtype=float) - settings.plan_padding
    return np.maximum(settings.tight_min_speed + settings.tight_slope * g, settings.tight_min_speed)


class Navigate(Activity):
    name = "navigate"

    def __init__(self, ctx, goal, position_tolerance: float | None = None,
                 heading_tolerance: float | None = None, max_speed: float | None = None,
                 timeout: float | None = None, max_blocked: float = 20.0, use_laser: bool = True):
        super().__init__(ctx, timeout)
        s = ctx.settings
        self.goal = goal
        self.position_tolerance = position_tolerance or s.position_tolerance
        self.heading_tolerance = heading_tolerance or s.heading_tolerance
        self.limits = Limits.from_settings(s, max_speed)
        self.max_blocked = max_blocked
        self.use_laser = use_laser
        self.stall_time = 2.0
        self.target: Pose2D | None = None
        self.path: np.ndarray | None = None
        self.follower: PathFollower | None = None
        self.replans = 0
        self.adjusted = 0.0              # metres the goal was moved to where the robot fits
        self.cleared = 0                 # earlier laser obstacles cleared at the start (no path with them)
        self.blocked_time = 0.0
        self.lag = ctx.settings.control_period
        self.waiting = False             # another robot stands on the goal (or backs off over it)
        self.yields = 0                  # times it stepped aside for another robot
        self._yield: dict | None = None  # stepping aside: the spot, since, hold_until, the real target
        self._blocker: tuple[float, float] | None = None     # centre of the nearest other robot
        self._block_start: float | None = None               # this block began (s), or the blocker last moved
        self._block_other: tuple[float, float] | None = None  # where the blocker stood then
        self._no_way = False             # the last replan found no path
        self._yield_retry = -math.inf    # no place to step aside to: look again then
        self._blocked_since: float | None = None
        self._last_poll: float | None = None
        self._user_timeout = timeout
        self.name = f"navigate to {goal.describe()}" if hasattr(goal, "describe") else "navigate"

    @property
    def planner(self) -> GridPlanner:
        planner = getattr(self.ctx, "_planner", None)
        if planner is None or planner.costmap is not self.ctx.costmap:
            planner = GridPlanner(self.ctx.costmap)
            self.ctx._planner = planner
        return planner

    # -- activity ---------------------------------------------------------
    def _on_start(self) -> None:
        self.ctx.update()
        self.target, heading = self._feasible(*self.goal.resolve(self.ctx))
        self._goal_heading = self.target.theta if heading else None
        start = self.ctx.pose()
        if self._user_timeout is None:
            straight = start.distance_to(self.target)
            self.timeout = 3.0 * straight / self.limits.max_speed + 20.0
        self.replans = 0
        self.blocked_time = 0.0
        self.stalled_time = 0.0
        self._stall_ref = None
        self._blocked_since = None
        self._last_poll = None
        self.yields = 0
        self._yield = None
        self._yield_retry = -math.inf
        self.closing = ClosingWatch()     # other robots coming closer from the side
        self._block_start = None
        self._no_way = False
        self.lag = self.ctx.settings.control_period      # s between polls, the worst lately
        self.follower = None             # a new start looks before it leaves
        try:
            self._plan(start)
        except NoPath as exc:
            # obstacles seen on an earlier way (robots, mostly) may have moved
            # on within their ttl: clear them, as Nav2's clear-costmap recovery
            # does, and try once more; the laser still stops the robot for
            # what is really there, and it replans around that
            seen = len(self.ctx.costmap.temporary_obstacles)
            if not seen:
                raise SkillFailure(SkillError.NAVIGATION_FAILED, str(exc)) from None
            self.ctx.costmap.clear_obstacles()
            try:
                self._plan(start)
            except NoPath:
                raise SkillFailure(SkillError.NAVIGATION_FAILED, str(exc)) from None
            self.cleared = seen

    def _plan(self, start: Pose2D) -> None:
        self.ctx.costmap.expire(self.ctx.clock.now())
        self.path = self.planner.plan((start.x, start.y), (self.target.x, self.target.y))
        old = self.follower
        fov = self.ctx.robot.laser_fov / 2.0
        blind = fov - 0.4 if self.use_laser else None
        # the side of the way out the laser sees whole: within 90 degrees of a direction
        look = max(fov - math.pi / 2.0, 0.2) if self.use_laser else None
        self.follower = PathFollower(self.path, self._goal_heading, self.limits,
                                     self.position_tolerance, self.heading_tolerance, blind_angle=blind,
                                     look_angle=look)
        if old is not None:      # keep the current velocity: no jump in the command
            self.follower.limiter.v = old.limiter.v.copy()
            self.follower.limiter.omega = old.limiter.omega
            self.follower.looked = old.looked

    def _step(self, now: float) -> Status:
        ctx = self.ctx
        src = ctx.pose_source
        if getattr(src, "lost", False):
            raise SkillFailure(SkillError.LOCALISATION_LOST,
                               f"localisation confidence {src.confidence:.2f} stayed below the limit")
        pose = ctx.pose()
        dt = ctx.settings.control_period if self._last_poll is None else max(now - self._last_poll, 1e-3)
        self._last_poll = now
        # the command holds until the next poll: late polls (a loaded machine,
        # a slow link) are a longer reaction time; the worst of the last few
        # seconds counts, up to the base's deadman time
        self.lag = poll_lag(self.lag, dt, ctx.settings.control_period)
        points = self._points(pose) if self.use_laser else None
        cap = None
        if points is not None:
            s = ctx.settings
            half_fov = ctx.robot.laser_fov / 2.0
            d_goal = math.hypot(self.target.x - pose.x, self.target.y - pose.y)
            here = np.array([pose.x, pose.y])
            static = ~unexplained(ctx, points + here)
            fixed, moving = points[static], points[~static]
            seen = moving                 # other robots in this scan
            now_t = ctx.clock.now()
            ctx.laser_memory.add(moving + here, now_t, (pose.x, pose.y), laser_view(ctx, pose, 3.0))
            self.closing.update(seen + here, here, now_t, ctx.robot.radius)
            closing = max(self.closing.closing, 0.0) if self.closing.active(now_t) else None
            remembered = ctx.laser_memory.relative(pose, now_t)
            # what was seen where the laser is blind now (another robot beside
            # and behind, when the direction of travel still lies in view)
            bearing = np.arctan2(remembered[:, 1], remembered[:, 0]) - pose.theta
            unseen = np.abs((bearing + np.pi) % (2.0 * np.pi) - np.pi) > half_fov
            moving = np.vstack([moving, remembered[unseen]])
            self._blocker = blocker(moving + here, (pose.x, pose.y), ctx.robot.radius)
            # a robot at a station keeps the strip it backs off into; a goal
            # another robot stands on (or backs off over) is not driven to
            moving = np.vstack([moving, station_zones(ctx, moving + here) - here])
            goal_taken = d_goal < GOAL_WAIT and occupied(moving, self.target.x - pose.x, self.target.y - pose.y,
                                                         ctx.robot.radius + GOAL_ROOM)
            self.waiting = goal_taken
            decel = self.limits.max_decel * 0.8
            # a loop polled late sees another robot late: meanwhile it may come
            # into the way from the side, not only along it (up to closing_speed)
            late = self.lag - s.control_period
            side = 0.08 + s.closing_speed * late if late > LATE else None

            def cap(ux: float, uy: float) -> float:
                if goal_taken:
                    return 0.0
                if d_goal < 0.5 and clear_distance(points, ux, uy, ctx.robot.radius, 0.02) >= d_goal + 0.02:
                    limit = math.inf      # the goal comes before the obstacle: no need to stop short
                else:
                    # mapped walls and stations; unmapped points may be robots coming closer
                    limit = min(speed_limit(fixed, ux, uy, ctx.robot.radius, s.safety_margin, 0.02, decel,
                                            self.lag),
                                speed_limit(moving, ux, uy, ctx.robot.radius, s.safety_margin + 0.07, 0.08,
                                            decel, self.lag + 0.1, s.closing_speed))
                    if side is not None:
                        limit = min(limit, speed_limit(seen, ux, uy, ctx.robot.radius, s.safety_margin + 0.07,
                                                       side, decel, self.lag + 0.1, s.closing_speed))
                if closing is not None:     # a robot beside the way coming closer: keep from it sideways too
                    limit = min(limit, radial_limit(seen, ux, uy, ctx.robot.radius, s.safety_margin, decel,
                                                    self.lag + 0.1, closing, RADIAL_NEAR))
                # the laser does not see behind: creep where it is blind, and
                # stop for what it saw there a moment ago
                if abs(wrap_angle(math.atan2(uy, ux) - pose.theta)) > half_fov - 0.4:
                    limit = min(limit, s.blind_speed,
                                speed_limit(remembered, ux, uy, ctx.robot.radius, s.safety_margin + 0.07,
                                            0.08, decel, self.lag),
                                self._map_limit(pose, ux, uy, decel))
                return limit
        self.follower.lookahead = self._lookahead(pose)
        self.follower.speed_limit = self._tight_speed(pose)
        vx, vy, w = self.follower.command(pose, dt, cap)
        if self._yield is not None:
            return self._stepping_aside(now, pose, dt, vx, vy, w)
        if self.follower.done:
            self.message = f"reached {self.goal.describe()}" if hasattr(self.goal, "describe") else "reached"
            return Status.SUCCESS
        blocked = self.follower.capped and self.follower.last_speed_wanted < 0.02
        stalled = self._stalled(now, vx, vy, w)
        if stalled:
            self.stalled_time += dt
            if self.stalled_time > self.max_blocked:
                raise SkillFailure(SkillError.NAVIGATION_FAILED,
                                   f"the robot does not move although commanded for {self.stalled_time:.0f} s")
            blocked = True
        if blocked:
            if self._blocked_since is None:
                self._blocked_since = now
            if self._block_start is None or self._blocker_moved():
                self._block_start, self._block_other = now, self._blocker
            self.blocked_time += dt
            if self._blocker is not None and self._user_timeout is None:
                self.timeout += dt       # waiting for another robot is not driving slowly (max_blocked limits it)
            if now - self._blocked_since >= ctx.settings.block_replan_after:
                self._replan_around(pose, points, now)
            if self._no_way and not stalled and self._blocker is not None and self.max_blocked >= PATIENT \
                    and self.yields < ctx.settings.max_yields and now >= self._yield_retry \
                    and now - self._block_start >= yield_delay(ctx.settings, getattr(ctx, "robot_number", 0),
                                                               (pose.x, pose.y), self._blocker) \
                    and self._step_aside(now, pose):
                ctx.backend.drive(0.0, 0.0, 0.0)
                return Status.RUNNING
            if self.blocked_time > self.max_blocked:
                why = " (another robot stands on the goal)" if self.waiting else ""
                raise SkillFailure(SkillError.NAVIGATION_FAILED,
                                   f"blocked for {self.blocked_time:.0f} s on the way to "
                                   f"({self.target.x:.2f}, {self.target.y:.2f}){why}")
        else:
            self._blocked_since = None
            self._block_start = None
            self._no_way = False
            if self._off_path(pose) > 0.6:
                self._try_plan(pose)
        ctx.backend.drive(vx, vy, w)
        return Status.RUNNING

    # -- helpers ----------------------------------------------------------
    def _feasible(self, target: Pose2D, heading: bool) -> tuple[Pose2D, bool]:
        """A goal inside a wall or station fails; one merely too close to
        one moves to the nearest spot where the robot fits (within 0.5 m)."""
        ctx = self.ctx
        # the exact distance to the map's walls and stations (0 inside one or
        # outside the field), not a 5-cm cell's: that is up to 3.5 cm off
        clear = float(ctx.map.clearance(target.x, target.y)[0])
        if clear <= 0.0:
            raise SkillFailure(SkillError.NAVIGATION_FAILED,
                               f"the goal ({target.x:.2f}, {target.y:.2f}) is blocked: inside a wall or station")
        need = standing_clearance(ctx)
        if clear >= need:
            return target, heading
        spot = nearest_fit(ctx.map, target.x, target.y, need + 0.01, reach=0.5)
        if spot is None:
            raise SkillFailure(SkillError.NAVIGATION_FAILED,
                               f"the goal ({target.x:.2f}, {target.y:.2f}) is blocked: no room for the robot")
        self.adjusted = math.hypot(spot[0] - target.x, spot[1] - target.y)
        return Pose2D(spot[0], spot[1], target.theta), heading

    def _lookahead(self, pose: Pose2D, longest: float = 0.5, shortest: float = 0.1) -> float:
        """The longest look-ahead (m) whose carrot the robot can head for in
        a straight line keeping as clear of walls and stations as the path
        does over that stretch: a carrot beyond a corner would pull the
        robot across the corner.  A robot off the path toward an obstacle
        gets the shortest look-ahead, which steers it back to the path."""
        cm, f = self.ctx.costmap, self.follower
        step = 0.25 * cm.resolution
        arc = f.points_at(f.progress + np.arange(0.0, longest + step, step))
        along = np.minimum.accumulate(cm.clearance_at(arc[:, 0], arc[:, 1]))
        for la in np.arange(longest, shortest - 1e-9, -0.05):
            k = int(round(la / step))
            need = min(float(along[k]), cm.lethal_radius + cm.inflation) - 0.01
            if cm.segment_clearance(pose.x, pose.y, arc[k, 0], arc[k, 1]) >= need:
                return float(la)
        return shortest

    def _tight_speed(self, pose: Pose2D, ahead: float = 1.2) -> float:
        """Speed (m/s) from which the robot can still slow down for the
        tight spots of the path ahead: where the path passes a wall or
        station with a gap of g metres the robot drives at most
        ``tight_speed(g)`` (a small tracking error must not become a
        contact at full speed)."""
        cm, f, s = self.ctx.costmap, self.follower, self.ctx.settings
        step = cm.resolution
        dist = np.arange(0.0, ahead + step, step)
        arc = f.points_at(f.progress + dist)
        gaps = cm.clearance_at(arc[:, 0], arc[:, 1]) - self.ctx.robot.radius
        here = float(cm.clearance_at(np.array([pose.x]), np.array([pose.y]))[0]) - self.ctx.robot.radius
        gaps[0] = min(gaps[0], here)
        v = tight_speed(gaps, s)
        return float(np.sqrt(v * v + 2.0 * self.limits.max_decel * 0.8 * dist).min())

    def _map_limit(self, pose: Pose2D, ux: float, uy: float, decel: float, reach: float = 0.4) -> float:
        """Speed (m/s) toward where the laser is blind that stops before the
        robot comes closer to a mapped wall or station than ``safety_margin``
        (or than it already is): the map sees there for it."""
        cm, step = self.ctx.costmap, 0.02
        d = np.arange(0.0, reach + step, step)
        gap = cm.clearance_at(pose.x + ux * d, pose.y + uy * d) - self.ctx.robot.radius
        bad = gap < min(float(gap[0]), self.ctx.settings.safety_margin) - 1e-3
        if not bad.any():
            return math.inf
        free = max(float(d[int(np.argmax(bad))]) - step, 0.0)
        return math.sqrt(2.0 * decel * free)

    def _stalled(self, now: float, vx: float, vy: float, w: float = 0.0) -> bool:
        """Commanded to drive (or to turn, looking before it leaves) for
        ``stall_time`` seconds without the odometry moving 2 cm (turning
        0.05 rad): something the laser does not see holds the robot."""
        odom = self.ctx.backend.odometry().pose
        driving, turning = math.hypot(vx, vy) >= 0.05, abs(w) >= 0.2
        if not (driving or turning) or self._stall_ref is None or \
                odom.distance_to(self._stall_ref[1]) > 0.02 or \
                abs(wrap_angle(odom.theta - self._stall_ref[1].theta)) > 0.05:
            self._stall_ref = (now, odom)
            return False
        return now - self._stall_ref[0] > self.stall_time

    def _points(self, pose: Pose2D) -> np.ndarray | None:
        """Laser points relative to the robot, in field-frame axes, moved
        from the time of the scan to now."""
        ctx = self.ctx
        try:
            scan = ctx.backend.laser_scan()
        except CapabilityError:
            self.use_laser = False
            return None
        if scan is None:
            return None
        pts = scan_points(scan, max_range=3.0)
        odom_now = ctx.backend.odometry().pose
        odom_then = ctx.odometry_history.at(scan.stamp)
        if odom_then is not None:
            pts = points_now(pts, odom_then, odom_now)
        return to_field(pts, Pose2D(0.0, 0.0, pose.theta))

    def _replan_around(self, pose: Pose2D, points: np.ndarray | None, now: float) -> None:
        ctx = self.ctx
        if points is not None and len(points):
            field_pts = points + np.array([pose.x, pose.y])
            near = np.hypot(points[:, 0], points[:, 1]) < 2.0
            others = field_pts[near & unexplained(ctx, field_pts)]
            ctx.costmap.add_obstacles(np.vstack([others, station_zones(ctx, others)]), now,
                                      ctx.settings.obstacle_ttl)
        self._blocked_since = now       # next attempt after another block period
        self._try_plan(pose)

    def _try_plan(self, pose: Pose2D) -> None:
        try:
            self._plan(pose)
            self.replans += 1
            self._no_way = False
        except NoPath:
            self._no_way = True   # keep waiting; the obstacles expire or move

    # -- giving way (see .yielding) ----------------------------------------
    def _blocker_moved(self, distance: float = 0.3) -> bool:
        """Whether the other robot is not where it stood when the wait for
        it began (it is doing something: its standing still is what counts)."""
        a, b = self._blocker, self._block_other
        if a is None or b is None:
            return a is not b
        return math.hypot(a[0] - b[0], a[1] - b[1]) > distance

    def _step_aside(self, now: float, pose: Pose2D) -> bool:
        """Head for a place out of the other robot's way; False (and try
        again a block period later) when there is none."""
        spot = yield_spot(self.ctx.costmap, self.planner, (pose.x, pose.y), self._blocker,
                          (self.target.x, self.target.y))
        if spot is None:
            self._yield_retry = now + self.ctx.settings.block_replan_after
            return False
        saved = (self.target, self._goal_heading, self.path, self.follower)
        self.target, self._goal_heading = Pose2D(spot[0], spot[1], pose.theta), None
        self.follower = None              # looks before it leaves
        try:
            self._plan(pose)
        except NoPath:
            self.target, self._goal_heading, self.path, self.follower = saved
            return False
        self.yields += 1
        self._yield = {"since": now, "hold_until": None, "blocked": 0.0, "real": saved[:2]}
        log.info("%s: blocked by another robot at (%.2f, %.2f) with no way round: stepping aside to "
                 "(%.2f, %.2f)", self.name, *self._blocker, *spot)
        return True

    def _stepping_aside(self, now: float, pose: Pose2D, dt: float, vx: float, vy: float, w: float) -> Status:
        """A poll while stepping aside: drive to the spot (or stop where the
        way there is blocked for 3 s), stand there ``yield_hold`` seconds,
        then plan the real way again."""
        y, ctx = self._yield, self.ctx
        if self.timeout is not None:
            self.timeout += dt                       # the time given to the other robot
        if y["hold_until"] is None:
            stuck = self.follower.capped and self.follower.last_speed_wanted < 0.02
            y["blocked"] = y["blocked"] + dt if stuck else 0.0
            if not (self.follower.done or y["blocked"] > 3.0 or now - y["since"] > 15.0):
                ctx.backend.drive(vx, vy, w)
                return Status.RUNNING
            y["hold_until"] = now + ctx.settings.yield_hold
        if now < y["hold_until"]:
            ctx.backend.drive(0.0, 0.0, 0.0)
            return Status.RUNNING
        self._yield = None
        self.target, self._goal_heading = y["real"]
        self._blocked_since = self._block_start = None
        self.blocked_time = 0.0          # made room: a new wait
        self._no_way = False
        self.follower = None
        try:
            self._plan(pose)
        except NoPath:
            self.ctx.costmap.clear_obstacles()
            try:
                self._plan(pose)
            except NoPath:       # the laser check and the replans take it from here
                self.path = np.array([[pose.x, pose.y], [self.target.x, self.target.y]])
                self.follower = PathFollower(self.path, self._goal_heading, self.limits,
                                             self.position_tolerance, self.heading_tolerance)
        ctx.backend.drive(0.0, 0.0, 0.0)
        return Status.RUNNING

    def _off_path(self, pose: Pose2D) -> float:
        f = self.follower
        p = f.point_at(f.progress)
        return math.hypot(pose.x - p[0], pose.y - p[1])
