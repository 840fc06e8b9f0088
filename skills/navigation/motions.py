"""Short motions without planning, closed on odometry: move by an offset
in the robot frame (backing away from a station), turn on the spot, and
turn while remembering what the laser sees (:class:`LookTurn`: a back-off
in the open turns so the way back lies in the laser's view first).

Both are non-blocking activities within the speed and acceleration limits.
They do not plan, so keep them short; :class:`MoveRelative` slows and stops
for what the laser sees in its way (behind the robot, where the laser is
blind, for the robots navigation saw there) and for a pressed bumper
(:class:`~skills.navigation.guard.MotionGuard`), and waits; a move that may
end early (a back-off: any distance gained is good) ends after
``give_up_after`` seconds blocked or at once when the bumper is pressed,
one that may not fails then.
"""
from __future__ import annotations

import math

import numpy as np

from rll_bt.backend import Pose2D, wrap_angle

from ..activity import Activity, Status
from ..errors import SkillError, SkillFailure
from .controller import Limits, VelocityLimiter, heading_command
from .guard import MotionGuard
from .safety import poll_lag


class MoveRelative(Activity):
    """Move by (dx, dy, dtheta) from where the robot stands when it starts
    (robot frame), at most ``speed`` m/s."""

    name = "move relative"

    def __init__(self, ctx, dx: float, dy: float = 0.0, dtheta: float = 0.0, speed: float = 0.15,
                 tolerance: float = 0.01, heading_tolerance: float = 0.02, timeout: float | None = None,
                 guard: bool = True, give_up_after: float = 4.0, partial: bool = False):
        if timeout is None:
            timeout = 2.0 * math.hypot(dx, dy) / speed + abs(dtheta) / 0.5 + give_up_after + 5.0
        super().__init__(ctx, timeout)
        self.offset = Pose2D(dx, dy, dtheta)
        self.speed = speed
        self.tolerance = tolerance
        self.heading_tolerance = heading_tolerance
        self.guard = MotionGuard(ctx) if guard else None
        self.give_up_after = give_up_after
        self.partial = partial          # blocked for good: success with the distance made

    def _on_start(self) -> None:
        self.goal = self.ctx.backend.odometry().pose.compose(self.offset)
        self.limiter = VelocityLimiter(Limits.from_settings(self.ctx.settings, self.speed))
        self._last = None
        self._blocked_since: float | None = None
        self.lag = self.ctx.settings.control_period     # s between polls, the worst lately

    def _step(self, now: float) -> Status:
        odom = self.ctx.backend.odometry().pose
        err = self.goal.relative_to(odom)
        d = math.hypot(err.x, err.y)
        if d <= self.tolerance and abs(err.theta) <= self.heading_tolerance:
            return Status.SUCCESS
        dt = self.ctx.settings.control_period if self._last is None else max(now - self._last, 1e-3)
        self._last = now
        self.lag = poll_lag(self.lag, dt, self.ctx.settings.control_period)
        lim = self.limiter.limits
        speed = min(self.speed, 1.5 * d, math.sqrt(2.0 * lim.max_decel * 0.8 * d))
        v = np.array([err.x, err.y]) / d * speed if d > 1e-9 else np.zeros(2)
        capped = False
        if self.guard is not None and self.partial and self.guard.bumped():
            # touching something: a move that may end early ends here, rather
            # than touch it again each time it gives way a little
            self.ctx.stop_base()
            self.message = f"stopped {d:.2f} m short: the bumper is pressed"
            return Status.SUCCESS
        if self.guard is not None and d > self.tolerance:
            vx, vy = self.guard.clamp(float(v[0]), float(v[1]), self.lag)
            capped = math.hypot(vx, vy) < speed - 1e-9
            v = np.array([vx, vy])
            if math.hypot(vx, vy) < 0.01:
                self._blocked_since = now if self._blocked_since is None else self._blocked_since
                if now - self._blocked_since >= self.give_up_after:
                    self.ctx.stop_base()
                    if self.partial:
                        self.message = f"stopped {d:.2f} m short: {self.guard.reason}"
                        return Status.SUCCESS
                    raise SkillFailure(SkillError.NAVIGATION_FAILED,
                                       f"{self.name} blocked {d:.2f} m short: {self.guard.reason}")
            else:
                self._blocked_since = None
        self.limiter.apply(v, heading_command(err.theta, lim), dt, emergency=capped)
        vx, vy, w = self.limiter.to_robot(0.0)
        self.ctx.backend.drive(vx, vy, w)
        return Status.RUNNING


class Turn(Activity):
    """Turn on the spot to the field heading ``heading`` (rad), or by
    ``by`` radians (any size: ``by=2*pi`` is a full turn to look around),
    at most ``omega`` rad/s."""

    name = "turn"

    def __init__(self, ctx, heading: float | None = None, by: float | None = None, omega: float = 0.8,
                 tolerance: float = 0.03, timeout: float | None = None):
        if (heading is None) == (by is None):
            raise ValueError("give exactly one of heading= or by=")
        span = abs(by) if by is not None else math.pi
        super().__init__(ctx, timeout if timeout is not None else span / omega * 2.0 + 5.0)
        self.heading = heading
        self.by = by
        self.omega = omega
        self.tolerance = tolerance

    def _on_start(self) -> None:
        odom = self.ctx.backend.odometry().pose
        if self.by is not None:
            self.remaining = float(self.by)
        else:
            self.remaining = wrap_angle(self.heading - self.ctx.pose().theta)
        self._last_theta = odom.theta
        self._omega = 0.0
        self._last = None

    def _step(self, now: float) -> Status:
        odom = self.ctx.backend.odometry().pose
        self.remaining -= wrap_angle(odom.theta - self._last_theta)
        self._last_theta = odom.theta
        if abs(self.remaining) <= self.tolerance:
            return Status.SUCCESS
        dt = self.ctx.settings.control_period if self._last is None else max(now - self._last, 1e-3)
        self._last = now
        s = self.ctx.settings
        lim = Limits(s.max_speed, min(self.omega, s.max_omega), s.max_accel, s.max_decel, s.max_alpha)
        want = heading_command(self.remaining, lim)
        step = s.max_alpha * dt
        self._omega += float(np.clip(want - self._omega, -step, step))
        self.ctx.backend.drive(0.0, 0.0, self._omega)
        return Status.RUNNING


class LookTurn(Turn):
    """A :class:`Turn` whose laser scans go into ``ctx.laser_memory`` as it
    turns (what the map does not explain: other robots), so that a move
    toward where the laser is blind afterwards (backing off) keeps off a
    robot that came to stand there unseen while this one looked the other way."""

    name = "look behind"

    def _on_start(self) -> None:
        super()._on_start()
        self.guard = MotionGuard(self.ctx)

    def _step(self, now: float) -> Status:
        self.guard.see()
        return super()._step(now)


def look_angle(ctx, half_width: float = 0.6) -> float:
    """How far (rad) to turn so that the strip straight behind the robot,
    ``half_width`` radians either side of its back, lies inside the laser's
    view (its field of view less 0.1 rad): 106 degrees for a 240-degree laser."""
    return max(math.pi + half_width - (ctx.robot.laser_fov / 2.0 - 0.1), 0.0)


def facing_station(ctx, reach: float = 0.35) -> bool:
    """Whether a station of the map stands straight ahead of the robot within
    its radius plus ``reach`` metres (lining up at it, docked or just backed
    off it).  Others keep out of the strip behind a robot at a station
    (:mod:`.others`); a robot in the open has no such strip kept for it."""
    pose = ctx.pose()
    ds = np.linspace(0.0, ctx.robot.radius + reach, 12)
    xs, ys = pose.x + math.cos(pose.theta) * ds, pose.y + math.sin(pose.theta) * ds
    walls = ctx.map.clearance(xs, ys, exclude=tuple(ctx.map.obstacles))
    every = ctx.map.clearance(xs, ys)
    return bool(((every < 0.02) & (walls > every + 1e-6)).any())
