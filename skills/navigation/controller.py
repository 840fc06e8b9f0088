"""Path following for the omnidirectional base.

The follower steers toward a carrot ``lookahead`` metres further along the
path (pure pursuit, but an omni base needs no curvature: it translates
straight at the carrot) and, independently, turns the body: along the
direction of travel while far from the goal (so the laser, which sees
240 degrees forward, looks where the robot goes) and to the goal heading
for the last ``align_distance`` metres - except while the direction of
travel lies more than ``blind_angle`` off the heading (where the laser is
blind) and more than ``blind_creep`` metres remain: then it turns to the
direction of travel first.  With ``look_angle`` set, a follower that has
not looked yet (a navigation's start: the robot stood still, maybe docked
at a station, while another robot came up in its blind sector) turns on the
spot until the direction of travel lies within ``look_angle`` of its
heading before it translates at all (turning a round robot touches
nothing), unless no more than ``align_distance`` is left (a short move to
a goal heading: the blind rule above holds); ``looked`` carries over to a
replanned follower.

Limits: translation speed ``max_speed`` (the rules' 0.7 m/s), the speed
from which the robot can still stop at the goal with ``max_decel``, the
speed from which it can still slow down for the coming path corners (a
corner turning by phi is taken at most at sqrt(2 max_accel
``corner_overshoot``) / sin(phi), so the robot swings out by no more than
about ``corner_overshoot`` metres while its velocity turns), an external
``speed_limit`` (navigation's tight spots ahead), and an
optional external cap (the laser safety check); the commanded velocity
vector changes by at most ``max_accel * dt`` (``max_decel * dt`` when
slowing, ``emergency_decel * dt`` when the laser check caps the speed);
angular speed and acceleration likewise.  Velocities are planned
in the field frame and sent in the robot frame.
"""
from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from rll_bt.backend import Pose2D, wrap_angle


@dataclass(frozen=True)
class Limits:
    max_speed: float = 0.7
    max_omega: float = 1.6
    max_accel: float = 0.8
    max_decel: float = 1.2
    max_alpha: float = 1.6
    emergency_decel: float = 1.5      # braking for an obstacle: what the base can do

    @classmethod
    def from_settings(cls, s, max_speed: float | None = None) -> Limits:
        return cls(min(max_speed or s.max_speed, s.max_speed), s.max_omega, s.max_accel,
                   s.max_decel, s.max_alpha, max(s.emergency_decel, s.max_decel))


class VelocityLimiter:
    """Holds the last command and limits how fast it changes."""

    def __init__(self, limits: Limits):
        self.limits = limits
        self.v = np.zeros(2)          # field frame, m/s
        self.omega = 0.0

    def reset(self) -> None:
        self.v[:] = 0.0
        self.omega = 0.0

    def apply(self, v_des: np.ndarray, omega_des: float, dt: float,
              emergency: bool = False) -> tuple[np.ndarray, float]:
        """Move the command toward (v_des, omega_des); ``emergency`` brakes
        at ``emergency_decel`` instead of ``max_decel``."""
        lim = self.limits
        speed = float(np.hypot(*v_des))
        if speed > lim.max_speed:
            v_des = v_des * (lim.max_speed / speed)
        dv = v_des - self.v
        if np.hypot(*v_des) > np.hypot(*self.v):
            a = lim.max_accel
        else:
            a = lim.emergency_decel if emergency else lim.max_decel
        n = float(np.hypot(*dv))
        if n > a * dt:
            dv = dv * (a * dt / n)
        self.v = self.v + dv
        omega_des = float(np.clip(omega_des, -lim.max_omega, lim.max_omega))
        dw = float(np.clip(omega_des - self.omega, -lim.max_alpha * dt, lim.max_alpha * dt))
        self.omega += dw
        return self.v.copy(), self.omega

    def to_robot(self, theta: float) -> tuple[float, float, float]:
        c, s = math.cos(theta), math.sin(theta)
        vx, vy = self.v
        return c * vx + s * vy, -s * vx + c * vy, self.omega


def heading_command(error: float, limits: Limits, gain: float = 2.0) -> float:
    """Angular speed toward a heading error (rad), able to stop in time."""
    w = gain * error
    stop = math.sqrt(2.0 * limits.max_alpha * 0.8 * abs(error))
    return float(np.clip(w, -min(stop, limits.max_omega), min(stop, limits.max_omega)))


class PathFollower:
    """Follows waypoints ``path`` (K, 2) to the last one, then turns to
    ``goal_theta`` (None: any heading)."""

    def __init__(self, path: np.ndarray, goal_theta: float | None, limits: Limits,
                 position_tolerance: float = 0.05, heading_tolerance: float = 0.05,
                 lookahead: float = 0.5, align_distance: float = 0.8, gain: float = 2.5,
                 blind_angle: float | None = None, blind_creep: float = 0.15,
                 corner_overshoot: float = 0.04, look_angle: float | None = None):
        self.path = np.asarray(path, dtype=float)
        if len(self.path) == 1:
            self.path = np.vstack([self.path, self.path])
        seg = np.diff(self.path, axis=0)
        self.seg_len = np.hypot(seg[:, 0], seg[:, 1])
        self.cum = np.concatenate([[0.0], np.cumsum(self.seg_len)])
        self.goal_theta = goal_theta
        self.limits = limits
        self.corner_speed = self._corner_speeds(corner_overshoot)
        self.position_tolerance = position_tolerance
        self.heading_tolerance = heading_tolerance
        self.lookahead = lookahead
        self.align_distance = align_distance
        self.gain = gain
        self.blind_angle = blind_angle
        self.blind_creep = blind_creep
        self.look_angle = look_angle
        self.looked = look_angle is None    # faced the direction of travel since the start
        self.limiter = VelocityLimiter(limits)
        self.progress = 0.0           # arc length of the closest path point
        self.done = False
        self.capped = False           # the last command was slowed by ``speed_cap``
        self.last_speed_wanted = 0.0
        self.speed_limit = math.inf   # m/s, set from outside (tight spots ahead)

    def _corner_speeds(self, overshoot: float) -> np.ndarray:
        """Highest speed (m/s) at each inner vertex of the path (inf at the ends)."""
        out = np.full(len(self.path), np.inf)
        seg = np.diff(self.path, axis=0)
        for i in range(1, len(self.path) - 1):
            a, b = seg[i - 1], seg[i]
            na, nb = float(np.hypot(*a)), float(np.hypot(*b))
            if na < 1e-9 or nb < 1e-9:
                continue
            sin_phi = abs(float(a[0] * b[1] - a[1] * b[0])) / (na * nb)
            if float(a @ b) < 0.0:         # turning back by more than 90 degrees
                sin_phi = 1.0
            if sin_phi > 1e-6:
                out[i] = math.sqrt(2.0 * self.limits.max_accel * overshoot) / sin_phi
        return out

    def _corner_limit(self, decel: float) -> float:
        """Speed from which the robot can still slow down to every coming
        corner's speed (looking 2 m ahead)."""
        i = int(np.searchsorted(self.cum, self.progress, side="right"))
        limit = math.inf
        while i < len(self.path) - 1 and self.cum[i] - self.progress <= 2.0:
            d = max(self.cum[i] - self.progress, 0.0)
            limit = min(limit, math.sqrt(self.corner_speed[i] ** 2 + 2.0 * decel * d))
            i += 1
        return limit

    @property
    def goal(self) -> np.ndarray:
        return self.path[-1]

    @property
    def length(self) -> float:
        return float(self.cum[-1])

    def remaining(self, pose: Pose2D) -> float:
        """Path length left from the closest point plus the offset to it."""
        return max(self.length - self.progress, 0.0)

    def _project(self, pose: Pose2D) -> None:
        p = np.array([pose.x, pose.y])
        a = self.path[:-1]
        d = self.path[1:] - a
        len2 = np.maximum((d * d).sum(axis=1), 1e-12)
        t = np.clip(((p - a) * d).sum(axis=1) / len2, 0.0, 1.0)
        proj = a + d * t[:, None]
        dist = np.hypot(*(proj - p).T)
        s = self.cum[:-1] + t * self.seg_len
        # only look forward (and a little back) from the current progress
        window = (s >= self.progress - 0.2) & (s <= self.progress + 2.0)
        if window.any():
            dist = np.where(window, dist, np.inf)
        i = int(np.argmin(dist))
        self.progress = max(self.progress, float(s[i]))

    def next_vertex(self) -> np.ndarray:
        """The first path vertex at least 5 cm beyond the current progress."""
        i = int(np.searchsorted(self.cum, self.progress + 0.05, side="left"))
        return self.path[min(i, len(self.path) - 1)].copy()

    def points_at(self, s: np.ndarray) -> np.ndarray:
        """Path points (K, 2) at arc lengths ``s`` (K,), clipped to the path."""
        s = np.clip(np.asarray(s, dtype=float), 0.0, self.length)
        i = np.clip(np.searchsorted(self.cum, s, side="right") - 1, 0, len(self.seg_len) - 1)
        seg = self.seg_len[i]
        t = np.where(seg > 1e-12, (s - self.cum[i]) / np.maximum(seg, 1e-12), 1.0)
        return self.path[i] + (self.path[i + 1] - self.path[i]) * t[:, None]

    def point_at(self, s: float) -> np.ndarray:
        s = min(max(s, 0.0), self.length)
        i = int(np.searchsorted(self.cum, s, side="right")) - 1
        i = min(max(i, 0), len(self.seg_len) - 1)
        if self.seg_len[i] <= 1e-12:
            return self.path[i + 1].copy()
        t = (s - self.cum[i]) / self.seg_len[i]
        return self.path[i] + (self.path[i + 1] - self.path[i]) * t

    def command(self, pose: Pose2D, dt: float,
                speed_cap: Callable[[float, float], float] | None = None) -> tuple[float, float, float]:
        """Body velocity (vx, vy, omega) for this control step.  ``speed_cap``
        gets the desired direction of travel (a field-frame unit vector) and
        returns the highest speed allowed along it (the laser check)."""
        lim = self.limits
        self._project(pose)
        p = np.array([pose.x, pose.y])
        to_goal = self.goal - p
        d_goal = float(np.hypot(*to_goal))
        remaining = max(self.length - self.progress, d_goal)
        if remaining <= self.lookahead or d_goal <= self.lookahead:
            target, dist = self.goal, d_goal
        else:
            target = self.point_at(self.progress + self.lookahead)
            dist = remaining
        direction = target - p
        n = float(np.hypot(*direction))
        speed = min(lim.max_speed, math.sqrt(2.0 * lim.max_decel * 0.8 * dist), self.gain * dist,
                    self._corner_limit(lim.max_decel * 0.8), self.speed_limit)
        wanted = speed
        self.capped = False
        if speed_cap is not None and n > 1e-9 and d_goal > self.position_tolerance:
            cap = speed_cap(direction[0] / n, direction[1] / n)
            if cap < 0.05 and target is not self.goal:
                # the carrot cuts a corner the robot is hugging: head for the
                # next waypoint instead, if that way is clearer
                vertex = self.next_vertex()
                alt = vertex - p
                m = float(np.hypot(*alt))
                if m > 1e-3:
                    alt_cap = speed_cap(alt[0] / m, alt[1] / m)
                    if alt_cap > cap:
                        target, direction, n, cap = vertex, alt, m, alt_cap
            if cap < speed:
                speed, self.capped = max(cap, 0.0), True
        self.last_speed_wanted = speed
        v_des = direction / n * speed if n > 1e-9 else np.zeros(2)
        at_position = d_goal <= self.position_tolerance
        if at_position:
            v_des = np.zeros(2)
        # heading
        travel = math.atan2(direction[1], direction[0]) if n > 1e-9 else pose.theta
        blind = (self.blind_angle is not None and wanted > 0.05 and d_goal > self.blind_creep
                 and abs(wrap_angle(travel - pose.theta)) > self.blind_angle)
        if not self.looked and n > 1e-9:
            if wanted > 0.05 and remaining > self.align_distance \
                    and abs(wrap_angle(travel - pose.theta)) > self.look_angle:
                blind, v_des = True, np.zeros(2)       # look first, on the spot
            else:
                self.looked = True
        if blind:
            want = travel            # never drive far where the laser cannot see: turn first
        elif self.goal_theta is not None and remaining <= self.align_distance:
            want = self.goal_theta
        elif wanted > 0.05 and n > 1e-9 and remaining > self.align_distance:
            want = math.atan2(direction[1], direction[0])
        else:
            want = self.goal_theta if self.goal_theta is not None else pose.theta
        err = wrap_angle(want - pose.theta)
        omega_des = heading_command(err, lim)
        heading_ok = self.goal_theta is None or abs(wrap_angle(self.goal_theta - pose.theta)) <= self.heading_tolerance
        if at_position and heading_ok:
            self.done = True
            self.limiter.reset()
            return 0.0, 0.0, 0.0
        if self.goal_theta is None and at_position:
            omega_des = 0.0
        self.limiter.apply(v_des, omega_des, dt, emergency=self.capped)
        return self.limiter.to_robot(pose.theta)
