"""Lining up with a station face: by its tag (visual servoing), then by
laser to the final distance.

:class:`AlignToTag` drives (on odometry) to the pose ``distance`` metres in
front of the tag, facing it, shifted along the face to the spot (belt,
shelf slot, slide).  Every new sighting of the tag gives that pose in the
odometry frame; the running mean of the last sightings is the target, so
the target sharpens as the robot closes in and odometry noise does not
matter over these few centimetres.  Once ``tag_sightings`` sightings are in,
the tag may leave the image (a shelf slot or the slide lies beside it) and
the robot finishes on odometry.  Tags come from ``ctx.tags`` (the
backend's oracle, or a perception source for rendered or real images).
It slows and waits for what the laser sees in its way (another robot
beside the station; :class:`~skills.navigation.guard.MotionGuard`).

:class:`Dock` covers the last stretch, where the camera no longer sees the
tag: it fits a line to the laser points of the face ahead, turns square to
it and drives until the face is ``distance`` metres from the robot centre,
holding its lateral position on odometry.
"""
from __future__ import annotations

import math

import numpy as np

from rll_bt.backend import CapabilityError, LaserScan, Pose2D

from ..activity import Activity, Status
from ..errors import SkillError, SkillFailure
from ..localisation.particles import circular_mean
from ..navigation.controller import Limits, VelocityLimiter, heading_command
from ..navigation.guard import MotionGuard
from ..navigation.safety import scan_points
from .places import Place, check_place, lateral_offset
from .tagview import tag_pose_in_robot


class AlignToTag(Activity):
    name = "align to tag"

    def __init__(self, ctx, place: Place, distance: float | None = None, window: int = 10,
                 at_spot: bool = True):
        m = ctx.settings.manipulation
        super().__init__(ctx, None)
        self.place = place
        self.at_spot = at_spot        # False: line up with the tag (the belt), not the spot beside it
        self.distance = m.coarse_distance if distance is None else distance
        self.window = window
        self.sightings = 0
        self.name = f"align to {place.describe()}"

    def _on_start(self) -> None:
        prof = self.ctx.profile
        check_place(self.place, prof)
        self.tag_id = prof.tag_ids(self.place.machine)[0 if self.place.side == "INPUT" else 1]
        self.lateral = lateral_offset(self.place, prof) if self.at_spot else 0.0
        self.targets: list[Pose2D] = []
        self.sightings = 0
        self.last_seen: float | None = None
        self._last_stamp = None
        self._settled_since: float | None = None
        self._last = None
        self.seen_other: set[int] = set()
        self.limiter = VelocityLimiter(Limits.from_settings(self.ctx.settings,
                                                            self.ctx.settings.manipulation.align_speed))
        self.guard = MotionGuard(self.ctx)

    def _look(self, odom: Pose2D, now: float) -> None:
        dets = self.ctx.tags.detections()
        if dets is None or dets.stamp == self._last_stamp:
            return
        self._last_stamp = dets.stamp
        tag = tag_pose_in_robot(dets, self.tag_id)
        if tag is None:
            self.seen_other.update(d.tag_id for d in dets.tags)
            return
        # from where the robot was when the frame was taken (a backend call or more ago)
        then = self.ctx.odometry_history.interpolate(dets.stamp)
        target = (odom if then is None else then).compose(tag.compose(Pose2D(self.distance, self.lateral, math.pi)))
        self.targets = (self.targets + [target])[-self.window:]
        self.sightings += 1
        self.last_seen = now

    def target(self) -> Pose2D:
        xs = np.array([[t.x, t.y, t.theta] for t in self.targets])
        w = np.full(len(xs), 1.0 / len(xs))
        return Pose2D(float(xs[:, 0].mean()), float(xs[:, 1].mean()), circular_mean(xs[:, 2], w))

    def _step(self, now: float) -> Status:
        m = self.ctx.settings.manipulation
        reading = self.ctx.backend.odometry()
        odom = reading.pose
        self.ctx.odometry_history.add(reading.stamp, odom)
        self._look(odom, now)
        waited = now - (self.last_seen if self.last_seen is not None else self.started_at)
        if waited > m.tag_search_time and self.sightings < m.tag_sightings:
            what = "lost sight of" if self.targets else "does not see"
            others = f" (sees tags {sorted(self.seen_other)})" if self.seen_other else ""
            raise SkillFailure(SkillError.ALIGN_FAILED,
                               f"the robot {what} tag {self.tag_id} of {self.place.describe()}{others}")
        if now - self.started_at > m.align_time:
            raise SkillFailure(SkillError.ALIGN_FAILED,
                               f"not lined up with {self.place.describe()} after {m.align_time:.0f} s")
        if not self.targets:
            self.ctx.backend.drive(0.0, 0.0, 0.0)
            return Status.RUNNING
        err = self.target().relative_to(odom)
        ok = (abs(err.x) <= m.align_tolerance and abs(err.y) <= m.align_tolerance
              and abs(err.theta) <= m.align_heading_tolerance and self.sightings >= m.tag_sightings)
        if ok:
            if self._settled_since is None:
                self._settled_since = now
            if now - self._settled_since >= m.align_settle:
                self.message = f"lined up with {self.place.describe()} from {self.sightings} sightings"
                return Status.SUCCESS
        else:
            self._settled_since = None
        dt = self.ctx.settings.control_period if self._last is None else max(now - self._last, 1e-3)
        self._last = now
        d = math.hypot(err.x, err.y)
        speed = min(m.align_speed, 1.2 * d)
        v = np.array([err.x, err.y]) / d * speed if d > 1e-9 else np.zeros(2)
        # stop for what is in the way (another robot beside the station);
        # the align time limit ends a wait that does not end
        vx, vy = self.guard.clamp(float(v[0]), float(v[1]))
        capped = math.hypot(vx, vy) < speed - 1e-9
        lim = self.limiter.limits
        self.limiter.apply(np.array([vx, vy]), heading_command(err.theta, Limits(lim.max_speed, 0.6, lim.max_accel,
                                                                                lim.max_decel, lim.max_alpha)),
                           dt, emergency=capped)
        vx, vy, w = self.limiter.to_robot(0.0)
        self.ctx.backend.drive(vx, vy, w)
        return Status.RUNNING


def fit_face(points: np.ndarray, half_width: float = 0.25, max_ahead: float = 1.2,
             iterations: int = 3, inlier: float = 0.02) -> tuple[float, float, int] | None:
    """Line x = a + b*y through the laser points (robot frame) straight ahead
    within ``half_width`` to the sides; returns (distance of the line from
    the robot centre, the robot's yaw relative to the face normal, inliers)
    or None when too few points."""
    ahead = points[(points[:, 0] > 0.0) & (points[:, 0] < max_ahead) & (np.abs(points[:, 1]) < half_width)]
    if len(ahead) < 8:
        return None
    near = ahead[:, 0] < ahead[:, 0].min() + 0.1        # the nearest surface
    pts = ahead[near]
    keep = np.ones(len(pts), dtype=bool)
    a = b = 0.0
    for _ in range(iterations):
        if keep.sum() < 8:
            return None
        b, a = np.polyfit(pts[keep, 1], pts[keep, 0], 1)
        keep = np.abs(pts[:, 0] - (a + b * pts[:, 1])) < inlier
    yaw = math.atan(b)
    return a * math.cos(yaw), yaw, int(keep.sum())


def face_centre(scan: LaserScan, width: float, max_range: float = 1.5, half_span: float = 0.6,
                inlier: float = 0.02, gap: float = 0.04, slack: float = 0.05, depth: float = 0.05,
                resolution: float = 0.03, fit_slack: float = 0.01, one_edge: bool = False) -> float | None:
    """Sideways position (robot frame, m) of the centre of the station face straight
    ahead, from where its laser points end on either side; None unless both edges
    are seen and nothing beside the station continues its face.

    First the run of points on the face's line through the one nearest straight
    ahead, unbroken (sorted sideways) by gaps over ``gap``, ``width`` long within
    ``slack`` (:func:`_point_run_centre`).  Where that finds none, the beams in scan
    order decide (:func:`_beam_run_centre`): at the face's edges the laser grazes it
    (70-80 degrees from straight ahead), where 1 cm of range noise moves a point
    sideways by about as much as the beams lie apart, so the sorted points leave
    holes in a face whose every beam hit it (2016 seed 19 at b5f82db: three beams
    left a 4.9 cm one 9 cm from an edge of C-DS's face; no centre, the put went
    4.4 cm beside the belt and the C3 fell to the floor).  The sorted points' answer
    stands where there is one, so the line-ups that had one do not move.

    ``one_edge`` (a robot docked beside the belt, in front of a slide or a shelf slot,
    whose far edge the laser grazes with beams 4-6 cm apart): the beams answer first,
    and when they pin only the near edge, the face is where a face ``width`` wide from it ends within the far
    edge's wider bounds; the near edge alone then places it (2016 seed 1 at 2750a55:
    four bases put beside C-RS2's slide fell to the floor, docked 0.4 m from a
    neighbour without a tag, where the map's pose alone lined the robot up).

    Docked at the belt, the last resort is the same: where neither run gives a centre
    because one edge is grazed (beams 5 cm apart where the face ends 0.4 m to the side
    of a laser 0.1 m from it, and range noise leaves a 4 cm hole in the sorted points
    there), the pinned edge places the face (2016 seed 11 at e913fe8: docked at C-DS's
    input 5 cm beside the belt, the laser saw the face from -0.28 to 0.42 m but gave no
    centre; the C3 and the C2 put there fell to the floor)."""
    points = scan_points(scan, max_range=max_range)
    fit = fit_face(points)
    if fit is None:
        return None
    if one_edge:      # the beams first: the sorted points' run answers 2-2.5 cm short there
        centre = _beam_run_centre(scan, fit, width, max_range, max(half_span, ONE_EDGE_SPAN), inlier,
                                  depth, resolution, fit_slack, one_edge=True)
        return centre if centre is not None else _point_run_centre(points, fit, width, half_span,
                                                                   inlier, gap, slack)
    centre = _point_run_centre(points, fit, width, half_span, inlier, gap, slack)
    if centre is None:
        centre = _beam_run_centre(scan, fit, width, max_range, half_span, inlier, depth, resolution,
                                  fit_slack)
    if centre is None:      # one edge pinned, the other grazed: the pinned one places the face
        centre = _beam_run_centre(scan, fit, width, max_range, max(half_span, ONE_EDGE_SPAN), inlier,
                                  depth, resolution, fit_slack, one_edge=True)
    return centre


#: m to either side within which the beams follow a face seen from beside the belt: the far
#: edge of a face seen from shelf slot 0 (0.32 m beside the belt) lies 0.67 m to the side
ONE_EDGE_SPAN = 0.8


def _face_line(fit: tuple[float, float, int]) -> tuple[float, float, float]:
    """(a, b, yaw) of the face's line x = a + b*y (robot frame) from :func:`fit_face`."""
    dist, yaw, _ = fit
    return dist / math.cos(yaw), math.tan(yaw), yaw


def _point_run_centre(points: np.ndarray, fit, width: float, half_span: float, inlier: float,
                      gap: float, slack: float) -> float | None:
    """The centre of the run of points on the face's line through the one nearest
    straight ahead, sorted sideways and cut at gaps over ``gap``; None unless the
    run is ``width`` long within ``slack``."""
    a, b, yaw = _face_line(fit)
    near = points[(np.abs(points[:, 1]) < half_span) & (points[:, 0] > 0.0)]
    on = near[np.abs(near[:, 0] - (a + b * near[:, 1])) < inlier]
    if len(on) < 8:
        return None
    ys = np.sort(on[:, 1])
    breaks = np.nonzero(np.diff(ys) > gap)[0]
    starts = np.concatenate([[0], breaks + 1])
    ends = np.concatenate([breaks, [len(ys) - 1]])
    mid = int(np.argmin(np.abs(ys)))
    k = int(np.nonzero((starts <= mid) & (ends >= mid))[0][0])
    lo, hi = float(ys[starts[k]]), float(ys[ends[k]])
    if abs((hi - lo) / math.cos(yaw) - width) > slack:
        return None
    return 0.5 * (lo + hi)


def _beam_run_centre(scan: LaserScan, fit, width: float, max_range: float, half_span: float,
                     inlier: float, depth: float, resolution: float, fit_slack: float,
                     one_edge: bool = False) -> float | None:
    """The centre of the face from the run of consecutive beams that hit it.

    A beam hits the face when its return lies within ``depth`` of the face's line
    (range noise, not a hole); the run goes through the beam on the line
    (``inlier``) nearest straight ahead.  Each edge lies between where the run's
    last beam and the next beam out cross the face's line (their angles are
    exact, their ranges are not), and that next beam must pass the face: no
    return, or one more than ``depth`` behind the line (one in front of it hides
    the edge).  Both edges must be pinned within ``resolution`` (the beams lie
    4-5 cm apart where a robot in front of a shelf slot sees the far edge: no
    answer there), and a face ``width`` wide must fit between them within
    ``fit_slack``, so something in line beside the face, which lengthens the
    run, gives no answer.  The centre: the middle of the positions a face that
    wide can take between the two edges' bounds."""
    r = np.asarray(scan.ranges, dtype=float)
    ang = scan.angles + scan.mount.theta
    c, s = np.cos(ang), np.sin(ang)
    ox, oy = scan.mount.x, scan.mount.y
    ok = np.isfinite(r) & (r >= scan.range_min) & (r < scan.range_max) & (r <= max_range)
    x, y = ox + np.where(ok, r, 0.0) * c, oy + np.where(ok, r, 0.0) * s
    a, b, _ = _face_line(fit)
    for refit in (True, False):
        res = np.where(ok, x - (a + b * y), np.inf)
        hit = ok & (np.abs(res) < depth) & (np.abs(y) < half_span) & (x > 0.0)
        on = hit & (np.abs(res) < inlier)
        if on.sum() < 8:
            return None
        mid = int(np.argmin(np.where(on, np.abs(y), np.inf)))
        lo = hi = mid
        while lo > 0 and hit[lo - 1]:
            lo -= 1
        while hi < len(r) - 1 and hit[hi + 1]:
            hi += 1
        if refit:         # the line through the whole run; range noise moves a point along
            # its beam, off the line by the noise times the cosine: the grazing beams pin the yaw
            run = on & (np.arange(len(r)) >= lo) & (np.arange(len(r)) <= hi)
            b, a = np.polyfit(y[run], x[run], 1, w=1.0 / np.maximum(np.abs(c[run]), 0.2))
    yaw = math.atan(b)
    with np.errstate(divide="ignore", invalid="ignore"):
        t = (a + b * oy - ox) / (c - b * s)          # along each beam to the face's line
    cross = np.where(t > 0.0, oy + t * s, np.nan)     # where it crosses it (robot y)
    edges, pinned = [], []
    for inner, outer in ((lo, lo - 1), (hi, hi + 1)):
        if outer < 0 or outer >= len(r) or (ok[outer] and res[outer] < depth):
            return None                               # the edge is not in view, or hidden
        span = (cross[inner], cross[outer])
        if not np.all(np.isfinite(span)):
            return None
        edges.append(span)
        pinned.append(abs(span[1] - span[0]) <= resolution)
    if not all(pinned) and not (one_edge and any(pinned)):
        return None                                   # not pinned
    (lo_in, lo_out), (hi_in, hi_out) = sorted(edges, key=lambda e: e[0])
    half = 0.5 * width * math.cos(yaw)
    low = max(min(lo_in, lo_out) + half, min(hi_in, hi_out) - half)
    high = min(max(lo_in, lo_out) + half, max(hi_in, hi_out) - half)
    if low - high > fit_slack:
        return None                                   # the face is not that wide
    if not all(pinned):                               # the pinned edge alone places the face
        near = edges[pinned.index(True)]
        if near[0] == min(lo_in, hi_in):
            return 0.5 * (min(near) + max(near)) + half
        return 0.5 * (min(near) + max(near)) - half
    return 0.5 * (low + high)


class Dock(Activity):
    name = "dock"

    def __init__(self, ctx, distance: float | None = None):
        m = ctx.settings.manipulation
        super().__init__(ctx, m.dock_time)
        self.distance = m.final_distance if distance is None else distance

    def _on_start(self) -> None:
        self.odom0 = self.ctx.backend.odometry().pose
        self._settled_since = None
        self._last = None
        self._last_stamp = None
        self._fit = None
        self._misses = 0

    def _step(self, now: float) -> Status:
        m = self.ctx.settings.manipulation
        try:
            scan = self.ctx.backend.laser_scan()
        except CapabilityError:
            raise SkillFailure(SkillError.ALIGN_FAILED, "docking needs a laser") from None
        if scan is not None and scan.stamp != self._last_stamp:
            self._last_stamp = scan.stamp
            fit = fit_face(scan_points(scan, max_range=1.5))
            if fit is None:
                self._misses += 1
                if self._misses >= 5:
                    raise SkillFailure(SkillError.ALIGN_FAILED, "no station face in front of the robot")
            else:
                self._misses = 0
                self._fit = (fit[0], fit[1], self.ctx.backend.odometry().pose)
        if self._fit is None:
            self.ctx.backend.drive(0.0, 0.0, 0.0)
            return Status.RUNNING
        # the last fit, moved on by the odometry since that scan
        odom = self.ctx.backend.odometry().pose
        dist0, yaw0, odom_fit = self._fit
        moved = odom.relative_to(odom_fit)
        dist, yaw = dist0 - moved.x, yaw0 + moved.theta
        e_d = dist - self.distance
        drift = odom.relative_to(self.odom0).y
        if abs(e_d) <= m.dock_tolerance and abs(yaw) <= m.align_heading_tolerance:
            if self._settled_since is None:
                self._settled_since = now
            if now - self._settled_since >= 0.2:
                self.ctx.backend.drive(0.0, 0.0, 0.0)
                self.message = f"docked {dist:.3f} m from the face"
                return Status.SUCCESS
        else:
            self._settled_since = None
        vx = float(np.clip(1.0 * e_d, -m.dock_speed, m.dock_speed))
        vy = float(np.clip(-1.0 * drift, -0.05, 0.05))
        w = float(np.clip(-1.5 * yaw, -0.3, 0.3))
        self.ctx.backend.drive(vx, vy, w)
        return Status.RUNNING
