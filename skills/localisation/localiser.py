"""The localisation service of one robot: an AMCL-style particle filter fed
from a backend's odometry and laser.

    loc = Localiser(backend, field_map, clock, AmclConfig.cheap(), seed=1)
    loc.initialise(Pose2D(4.5, -0.5, math.pi / 2))
    ...
    loc.update()              # every control tick; cheap when not moved
    est = loc.estimate()      # pose (field frame), covariance, confidence

The filter runs only after ``update_min_d`` metres or ``update_min_a``
radians of odometry (as AMCL does), and, while its confidence is low, every
``still_update_period`` seconds when standing.  Each filter update moves the
particles to the odometry of the *scan's* time (a scan is up to one laser
period old; at 0.7 m/s that is 7 cm), from a short history of the odometry
kept at every :meth:`Localiser.update` call.  Between filter updates the
pose is the last estimate moved on by odometry, so ``pose()`` is smooth and
current at every tick.

Relocalising (:class:`~skills.localisation.relocalise.Relocalise`) may
:meth:`Localiser.boost` the particle and beam counts for a while, and starts
a global search with a prior around the last estimate, so that in a
mirror-symmetric field the hypothesis on the robot's own side wins.

A scan that pins the position in one direction only (beside a long wall,
nothing else mapped within the laser's range: :mod:`.observability`) says
nothing along the other; there the pose follows the odometry from the last
estimate (the whole cloud is moved along that direction onto it), instead
of drifting with the cloud, and the cloud's spread along it, which grows with
the motion noise, lowers the confidence as the odometry's error grows.
A global search with no prior at all (a restarted robot) leaves the localiser
``side_unsure``: the laser cannot tell a place from its mirror image in the
other half, so :attr:`Localiser.confidence` stays below the trees' ``localised``
level until a station's tag confirms the pose (:meth:`Localiser.confirm`).
"""
from __future__ import annotations

import math
from collections import deque
from dataclasses import dataclass, replace

import numpy as np

from rll_bt.backend import Backend, CapabilityError, LaserScan, Pose2D
from rll_bt.clock import Clock

from ..maps import FieldMap, cast_rays
from .config import AmclConfig
from .motion import odometry_step
from .observability import beam_normals, weakest_direction
from .particles import ParticleFilter


@dataclass(frozen=True)
class PoseEstimate:
    """The localiser's belief.  ``pose`` in the field frame; ``covariance``
    3x3 over (x [m], y [m], theta [rad]); ``confidence`` 0..1 combines the
    share of weight in the main cluster, its spread and how well the scan
    agrees with the map from that pose (``fit``, see :meth:`Localiser.fit`)."""
    stamp: float
    pose: Pose2D
    covariance: np.ndarray
    confidence: float
    fit: float
    particles: int
    lost: bool = False

    @property
    def std_xy(self) -> float:
        return float(math.sqrt(max(self.covariance[0, 0] + self.covariance[1, 1], 0.0)))

    @property
    def std_theta(self) -> float:
        return float(math.sqrt(max(self.covariance[2, 2], 0.0)))


def select_beams(scan: LaserScan, count: int) -> tuple[np.ndarray, np.ndarray]:
    """(ranges, angles in the laser frame) of up to ``count`` beams spread
    evenly over the scan, without readings outside [range_min, range_max)."""
    ranges = np.asarray(scan.ranges, dtype=float)
    n = len(ranges)
    if n == 0:
        return np.zeros(0), np.zeros(0)
    idx = np.unique(np.linspace(0, n - 1, min(count, n)).round().astype(int))
    r = ranges[idx]
    ok = np.isfinite(r) & (r >= scan.range_min) & (r < scan.range_max)
    return r[ok], scan.angle_min + scan.angle_increment * idx[ok]


def beam_endpoints(ranges: np.ndarray, angles: np.ndarray, mount: Pose2D) -> np.ndarray:
    """Beam endpoints (M, 2) in the robot frame."""
    a = angles + mount.theta
    return np.column_stack([mount.x + ranges * np.cos(a), mount.y + ranges * np.sin(a)])


class Localiser:
    def __init__(self, backend: Backend, field_map: FieldMap, clock: Clock,
                 config: AmclConfig | None = None, seed: int = 0):
        self.backend = backend
        self.map = field_map
        self.clock = clock
        self.config = config or AmclConfig.standard()
        self.filter = ParticleFilter(field_map, self.config, seed)
        self._odom_at_update: Pose2D | None = None     # odometry at the last filter update
        self._pose_at_update: Pose2D | None = None     # estimate at the last filter update
        self._last_filter_time = -math.inf
        self._last_scan_stamp: float | None = None
        self._reset_stamp = -math.inf
        self._low_streak = 0
        self._estimate: PoseEstimate | None = None
        self.filter_updates = 0
        self.last_contradiction = 0.0      # share of beams through mapped walls at the estimate
        self.held = 0                      # filter updates whose pose along one direction followed odometry
        self._odom_history: deque[tuple[float, Pose2D]] = deque(maxlen=32)
        # a global search with nothing known (a restarted robot): the laser cannot tell a place from its
        # mirror image in the other team's half, so the pose is not trusted before a tag confirmed it
        self.side_unsure = False
        self._base_config = self.config

    # -- set-up -----------------------------------------------------------
    def initialise(self, pose: Pose2D, sigma: tuple[float, float, float] = (0.1, 0.1, 0.1)) -> None:
        """Start from a known pose (a Gaussian with the given std devs)."""
        self.filter.initialise(pose, sigma)
        self._reset(pose)

    def initialise_global(self, prior: Pose2D | None = None, prior_sigma: float = 2.5) -> None:
        """Start lost: particles over all free space; with ``prior`` (the
        last believed pose) weighted by a broad Gaussian around it
        (``prior_sigma`` metres), which decides between look-alike places
        far apart (the mirror image of the robot's place in the other
        team's half) while any place can still win on the evidence."""
        self.filter.initialise_uniform()
        if prior is None:
            self.side_unsure = True
        if prior is not None:
            p = self.filter.particles
            d2 = (p[:, 0] - prior.x) ** 2 + (p[:, 1] - prior.y) ** 2
            w = np.exp(-0.5 * d2 / prior_sigma ** 2)
            self.filter.weights = w / w.sum()
        self._reset(None)

    def boost(self, particles: int, beams: int | None = None) -> None:
        """Use up to ``particles`` particles (and ``beams`` beams) until
        :meth:`unboost`: for relocalising, where the particles must cover a
        wide area; KLD sampling shrinks the set again as it converges."""
        cfg = self._base_config
        self.config = replace(cfg, particles=max(particles, cfg.particles),
                              max_particles=max(particles, cfg.max_particles),
                              beams=max(beams or cfg.beams, cfg.beams))
        self.filter.config = self.config

    def unboost(self) -> None:
        """Back to the configured counts (the next resample trims the set)."""
        self.config = self._base_config
        self.filter.config = self.config

    def _reset(self, pose: Pose2D | None) -> None:
        self._odom_at_update = self.backend.odometry().pose
        self._reset_stamp = self.clock.now()
        self._last_scan_stamp = None
        self._pose_at_update = pose
        self._last_filter_time = -math.inf
        self._low_streak = 0
        if pose is not None:
            est = self.filter.estimate()
            # a pose given with a small spread (the operator's start pose) is
            # as trusted as its spread says, until the laser has a say
            std = math.sqrt(max(est.covariance[0, 0] + est.covariance[1, 1], 0.0))
            trust = 1.0 / (1.0 + (std / 0.15) ** 2)
            self._estimate = PoseEstimate(self.clock.now(), pose, est.covariance, trust, 0.0,
                                          len(self.filter.particles))
        else:
            self._estimate = None

    @property
    def initialised(self) -> bool:
        return len(self.filter.particles) > 0

    # -- running ----------------------------------------------------------
    def update(self, force: bool = False) -> bool:
        """Run the filter if the robot moved enough (or ``force``); returns
        whether it ran.  Cheap otherwise: one odometry read."""
        if not self.initialised:
            raise RuntimeError("initialise the localiser first")
        reading = self.backend.odometry()
        odom = reading.pose
        if not self._odom_history or self._odom_history[-1][0] != reading.stamp:
            self._odom_history.append((reading.stamp, odom))
        du, dv, dw = odometry_step(self._odom_at_update, odom)
        moved = math.hypot(du, dv) >= self.config.update_min_d or abs(dw) >= self.config.update_min_a
        now = self.clock.now()
        still = (not moved and self.config.still_update_period is not None
                 and now - self._last_filter_time >= self.config.still_update_period
                 and (self._estimate is None or self._estimate.confidence < self.config.confident))
        if not (moved or still or force):
            return False
        scan = self._scan()
        if scan is None or scan.stamp == self._last_scan_stamp or scan.stamp < self._reset_stamp - 1e-9:
            return False          # no scan, the one already used, or one from before a re-initialisation
        self._last_scan_stamp = scan.stamp
        odom = self._odometry_at(scan.stamp, odom)        # where the robot was when the scan was taken
        du, dv, dw = odometry_step(self._odom_at_update, odom)
        # where odometry alone puts the robot (from a trusted estimate): kept along a direction the scan misses
        tracked = (self._estimate is not None and not self._estimate.lost and not self.side_unsure
                   and self._pose_at_update is not None and self.config.hold_below > 0)
        predicted = self.pose_with(odom) if tracked else None
        self.filter.predict((du, dv, dw))
        if not moved:
            self.filter.jitter(*self.config.still_jitter)
        ranges, angles = select_beams(scan, self.config.beams)
        beams = beam_endpoints(ranges, angles, scan.mount)
        self.filter.correct(beams)
        if self.filter.updates % self.config.resample_interval == 0:
            self.filter.allow_injection = (self._estimate is None
                                           or self.last_contradiction > self.config.inject_above_contradiction)
            self.filter.resample(searching=self._low_streak >= self.config.lost_updates)
        self._odom_at_update = odom
        self._last_filter_time = now
        self.filter_updates += 1
        self._estimate = self._make_estimate(now, ranges, angles, scan.mount)
        if predicted is not None:
            self._estimate = self._hold_unseen(self._estimate, predicted, ranges, angles, scan.mount)
        self._pose_at_update = self._estimate.pose
        return True

    def _hold_unseen(self, est: PoseEstimate, predicted: Pose2D, ranges, angles, mount: Pose2D) -> PoseEstimate:
        """``est`` with its position along a direction the scan does not pin (seen from
        ``predicted``) moved onto ``predicted``, and every particle with it."""
        normals = beam_normals(predicted, ranges, angles, mount, self.map.segments(), self.config.fit_tolerance)
        evidence, u = weakest_direction(normals)
        if evidence >= self.config.hold_below:
            return est
        shift = (predicted.x - est.pose.x) * u[0] + (predicted.y - est.pose.y) * u[1]
        self.filter.particles[:, :2] += shift * u
        self.held += 1
        pose = Pose2D(est.pose.x + shift * u[0], est.pose.y + shift * u[1], est.pose.theta)
        return replace(est, pose=pose)

    def _odometry_at(self, stamp: float, now_pose: Pose2D) -> Pose2D:
        """The odometry pose at ``stamp``: interpolated in the history (the
        newest one when the stamp is newer, ``now_pose`` without history)."""
        h = self._odom_history
        if not h or stamp >= h[-1][0]:
            return now_pose
        if stamp <= h[0][0]:
            return h[0][1]
        for (t0, p0), (t1, p1) in zip(reversed(list(h)[:-1]), reversed(list(h)[1:])):
            if t0 <= stamp <= t1:
                f = 0.0 if t1 <= t0 else (stamp - t0) / (t1 - t0)
                step = p1.relative_to(p0)
                return p0.compose(Pose2D(step.x * f, step.y * f, step.theta * f))
        return now_pose

    def _scan(self) -> LaserScan | None:
        try:
            return self.backend.laser_scan()
        except CapabilityError:
            return None

    def _make_estimate(self, now: float, ranges, angles, mount: Pose2D) -> PoseEstimate:
        previous = self._estimate.pose if self._estimate is not None else None
        cl = self.filter.estimate(previous)
        fit = self.fit(cl.pose, ranges, angles, mount)
        std = math.sqrt(max(cl.covariance[0, 0] + cl.covariance[1, 1], 0.0))
        spread = 1.0 / (1.0 + (std / 0.15) ** 2)
        confidence = float(cl.weight * fit * spread)
        self._low_streak = self._low_streak + 1 if confidence < self.config.lost else 0
        lost = self._low_streak >= self.config.lost_updates
        return PoseEstimate(now, cl.pose, cl.covariance, confidence, fit, len(self.filter.particles), lost)

    def fit(self, pose: Pose2D, ranges: np.ndarray, angles: np.ndarray, mount: Pose2D) -> float:
        """Agreement (0..1) of a scan with the map seen from ``pose``.

        Only beams expected to reach at least 0.3 m count.  Beams cut short
        are neutral (unmapped stations, other robots); beams that reach past
        a wall contradict the pose; beams that reach past a mapped station
        face by less than ``station_slack`` metres are neutral too (a
        station's mapped pose may be off, from a zone centre or a rough
        sighting: only the walls are certain), deeper they contradict it;
        beams that end at the expected wall or station
        support it: agreement = (1 - long / 0.2) * min(1, match / 0.3), each
        factor clipped to [0, 1].  Sets ``last_contradiction`` (the share of
        beams through walls), which gates the random injection."""
        if len(ranges) == 0:
            self.last_contradiction = 0.0
            return 0.0
        origin = pose.compose(mount)
        # exact ranges to the map's segments: a raster wall sits up to a cell
        # off, and a beam grazing it would read as passing through it
        rays = (np.array([origin.x, origin.y]), angles + origin.theta)
        rmax = self.filter.field.range_max
        walls = cast_rays(*rays, self.map.wall_segments(), rmax)
        expected = np.minimum(walls, cast_rays(*rays, self.map.obstacle_segments(), rmax)) \
            if self.map.obstacles else walls
        # beams ending next to the robot (docked at a station) say little about the pose
        judged = expected >= 0.3
        if not judged.any():
            self.last_contradiction = 0.0
            return 1.0
        r, e, w = ranges[judged], expected[judged], walls[judged]
        tol = self.config.fit_tolerance
        match = float(np.mean((np.abs(r - e) <= tol) | (np.abs(r - w) <= tol)))
        long = float(np.mean((r > w + tol) | (r > e + self.config.station_slack)))
        self.last_contradiction = long
        return float(np.clip(1.0 - long / 0.2, 0.0, 1.0) * min(1.0, match / 0.3))

    def fit_now(self, pose: Pose2D) -> float | None:
        """:meth:`fit` of the latest scan (the configured number of beams)
        seen from ``pose``; None without a scan.  For checking a pose from
        elsewhere (a tag sighting) against the laser."""
        scan = self._scan()
        if scan is None:
            return None
        ranges, angles = select_beams(scan, self.config.beams)
        return self.fit(pose, ranges, angles, scan.mount)

    # -- results ----------------------------------------------------------
    def estimate(self) -> PoseEstimate | None:
        """The belief at the current odometry (the last filter estimate moved
        on by the odometry since), or None before the first estimate."""
        if self._estimate is None:
            return None
        return PoseEstimate(self._estimate.stamp, self.pose(), self._estimate.covariance,
                            self._estimate.confidence, self._estimate.fit,
                            self._estimate.particles, self._estimate.lost)

    def pose(self) -> Pose2D | None:
        return self.pose_with(self.backend.odometry().pose)

    def pose_with(self, odom: Pose2D) -> Pose2D | None:
        """The pose when the odometry read ``odom`` (the estimate moved on,
        or back, by the odometry since the last update)."""
        if self._pose_at_update is None:
            return None
        step = odom.relative_to(self._odom_at_update)
        return self._pose_at_update.compose(step)

    def confirm(self) -> None:
        """A station's tag confirmed the pose: which half the robot is in is known."""
        self.side_unsure = False

    @property
    def confidence(self) -> float:
        """The estimate's confidence, held below ``unsure_side`` while the side is unsure
        (what the agent reports and the trees' ``localised`` check read)."""
        c = 0.0 if self._estimate is None else self._estimate.confidence
        return min(c, self.config.unsure_side) if self.side_unsure else c

    @property
    def lost(self) -> bool:
        return self._estimate is not None and self._estimate.lost
