"""The particle filter: predict, weigh, resample (KLD, augmented MCL), estimate.

Pure algorithm, no backend: steps come in as odometry displacements and
beam endpoints in the robot frame.  All randomness comes from one seeded
``numpy.random.Generator`` (filterpy's resampler included, see
:mod:`.resample`), so a filter is deterministic for its seed.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from rll_bt.backend import Pose2D
from rll_bt.rules import ROBOT

from ..maps import FieldMap
from .config import AmclConfig
from .kld import bin_keys, kld_prefix_length
from .resample import draw
from .sensor import LikelihoodField


@dataclass(frozen=True)
class ClusterEstimate:
    pose: Pose2D
    covariance: np.ndarray      # 3x3 over x [m], y [m], theta [rad]
    weight: float               # share of the total weight in the cluster, 0..1


def circular_mean(theta: np.ndarray, w: np.ndarray) -> float:
    return math.atan2(float(np.sum(w * np.sin(theta))), float(np.sum(w * np.cos(theta))))


class ParticleFilter:
    """``particles`` (N, 3) as x, y, theta in the field frame; ``weights``
    (N,) summing to 1."""

    def __init__(self, field_map: FieldMap, config: AmclConfig | None = None, seed: int = 0,
                 robot_radius: float = ROBOT.radius):
        self.map = field_map
        self.config = config or AmclConfig.standard()
        self.rng = np.random.default_rng(seed)
        self.robot_radius = robot_radius
        self.field = LikelihoodField(field_map, self.config.grid_resolution, self.config.sigma_hit,
                                     self.config.z_hit, self.config.z_rand)
        self.particles = np.zeros((0, 3))
        self.weights = np.zeros(0)
        self.w_slow: float | None = None
        self.w_fast: float | None = None
        self.last_w_avg = 0.0
        self.injected = 0
        self.updates = 0
        #: set by the localiser: inject only while the scan contradicts the
        #: estimate (a symmetric field would otherwise grow a mirror pose)
        self.allow_injection = True
        self._free: tuple[int, np.ndarray] | None = None

    # -- initialisation ---------------------------------------------------
    def initialise(self, pose: Pose2D, sigma: tuple[float, float, float] = (0.1, 0.1, 0.1),
                   count: int | None = None) -> None:
        """A Gaussian cloud around ``pose`` (standard deviations in m, m, rad)."""
        n = count or self.config.particles
        p = self.rng.standard_normal((n, 3)) * np.asarray(sigma) + np.array([pose.x, pose.y, pose.theta])
        p[:, 2] = (p[:, 2] + np.pi) % (2 * np.pi) - np.pi
        self._set(p)

    def initialise_uniform(self, count: int | None = None) -> None:
        """Global localisation: particles spread over all free space."""
        self._set(self.random_poses(count or self.config.max_particles))

    def _set(self, particles: np.ndarray) -> None:
        self.particles = particles
        self.weights = np.full(len(particles), 1.0 / len(particles))
        self.w_slow = self.w_fast = None

    def random_poses(self, n: int) -> np.ndarray:
        """``n`` poses drawn uniformly over cells where the robot fits."""
        if self._free is None or self._free[0] != self.map.version:
            dist = self.map.distance(self.config.grid_resolution)
            ok = (dist.distance >= self.robot_radius) & self.map.arena_mask(self.config.grid_resolution)
            rows, cols = np.nonzero(ok)
            xs, ys = dist.spec.centre_of(rows, cols)
            self._free = (self.map.version, np.stack([xs, ys], axis=1))
        free = self._free[1]
        if len(free) == 0:
            raise ValueError("the map has no free space for the robot")
        pick = free[self.rng.integers(0, len(free), n)]
        jitter = (self.rng.random((n, 2)) - 0.5) * self.config.grid_resolution
        theta = self.rng.uniform(-np.pi, np.pi, n)
        return np.column_stack([pick + jitter, theta])

    # -- the three steps --------------------------------------------------
    def predict(self, step: tuple[float, float, float]) -> None:
        self.config.motion.sample(self.particles, step, self.rng)

    def jitter(self, sigma_xy: float, sigma_theta: float) -> None:
        """Roughening for updates without motion."""
        n = len(self.particles)
        self.particles[:, :2] += self.rng.standard_normal((n, 2)) * sigma_xy
        th = self.particles[:, 2] + self.rng.standard_normal(n) * sigma_theta
        self.particles[:, 2] = (th + np.pi) % (2 * np.pi) - np.pi

    def correct(self, beams: np.ndarray) -> float:
        """Weigh by beam endpoints ``beams`` (M, 2, robot frame); returns the
        average per-beam likelihood (geometric mean over beams, weighted mean
        over particles) that drives recovery."""
        self.field.refresh()
        if len(beams) == 0:
            return self.last_w_avg
        lp = self.field.log_likelihood(self.particles, beams)
        s = lp.sum(axis=1, dtype=np.float64)
        m = len(beams)
        # the recovery statistic ignores each particle's worst beams: readings
        # of unmapped stations and robots must not look like a lost pose
        keep = max(1, int(round(m * (1.0 - self.config.trim_beams))))
        best = -np.partition(-lp, keep - 1, axis=1)[:, :keep] if keep < m else lp
        w_avg = float(np.sum(self.weights * np.exp(best.mean(axis=1, dtype=np.float64))))
        lw = np.log(np.maximum(self.weights, 1e-300)) + s / self.config.beam_correlation
        # a robot is never inside an obstacle or outside the field
        clearance = self.map.distance(self.config.grid_resolution).lookup(self.particles[:, 0],
                                                                          self.particles[:, 1])
        lw = np.where(clearance < 0.5 * self.robot_radius, lw - 30.0, lw)
        lw -= lw.max()
        w = np.exp(lw)
        self.weights = w / w.sum()
        self.last_w_avg = w_avg
        c = self.config
        if self.w_slow is None:
            self.w_slow = self.w_fast = w_avg
        else:
            self.w_slow += c.alpha_slow * (w_avg - self.w_slow)
            self.w_fast += c.alpha_fast * (w_avg - self.w_fast)
        self.updates += 1
        return w_avg

    def _near(self, xy: np.ndarray, theta: float) -> np.ndarray:
        c, p = self.config, self.particles
        dth = (p[:, 2] - theta + np.pi) % (2 * np.pi) - np.pi
        return (np.hypot(p[:, 0] - xy[0], p[:, 1] - xy[1]) <= c.cluster_xy) & (np.abs(dth) <= c.cluster_theta)

    @property
    def injection_probability(self) -> float:
        """Augmented MCL: the share of random particles at the next resample,
        1 - w_fast / (recovery_ratio * w_slow), clipped to [0, 1]; a ratio
        below 1 keeps passing robots and unmapped stations from triggering it."""
        c = self.config
        if c.alpha_slow <= 0 or not self.w_slow:
            return 0.0
        return float(min(max(1.0 - self.w_fast / (c.recovery_ratio * self.w_slow), 0.0), 1.0))

    @property
    def effective_size(self) -> float:
        return float(1.0 / np.sum(self.weights ** 2))

    def resample(self, searching: bool = False) -> None:
        """KLD-adaptive systematic resampling with random injection.
        ``searching`` (the pose is lost): keep the full ``max_particles`` and
        inject at least ``lost_injection`` of them at random, so the true
        pose is found again even after the filter settled on a wrong one."""
        c = self.config
        idx = draw(self.weights, c.max_particles, self.rng)
        new = self.particles[idx]
        if c.min_particles < c.max_particles and not searching:
            keys = bin_keys(new, c.kld_bin_xy, c.kld_bin_theta)
            n = kld_prefix_length(keys, c.min_particles, c.max_particles, c.kld_epsilon, c.kld_z)
            new = new[:n]
        new = np.array(new)
        p_inj = min(self.injection_probability, c.max_injection) if self.allow_injection else 0.0
        if searching:
            p_inj = max(p_inj, c.lost_injection)
        inject = int(self.rng.binomial(len(new), p_inj))
        if inject:
            new[:inject] = self.random_poses(inject)
        self.injected = inject
        self.particles = new
        self.weights = np.full(len(new), 1.0 / len(new))

    # -- estimate ---------------------------------------------------------
    def estimate(self, previous: Pose2D | None = None) -> ClusterEstimate:
        """Mean and covariance of the heaviest cluster: the particles within
        ``cluster_xy`` / ``cluster_theta`` of the heaviest histogram bin.
        With ``previous`` (the last estimate), its own cluster is kept while
        it holds at least half the weight of the heaviest one, so a few
        injected particles that happen to fit do not make the pose jump."""
        c = self.config
        p, w = self.particles, self.weights
        keys = bin_keys(p, c.cluster_xy, c.cluster_theta)
        uniq, inv = np.unique(keys, return_inverse=True)
        best = int(np.argmax(np.bincount(inv, weights=w, minlength=len(uniq))))
        in_bin = inv == best
        wb = w[in_bin]
        near = self._near(np.array([(wb[:, None] * p[in_bin, :2]).sum(axis=0) / wb.sum()]).ravel(),
                          circular_mean(p[in_bin, 2], wb)) | in_bin
        if previous is not None:
            around = self._near(np.array([previous.x, previous.y]), previous.theta)
            if not (around & near).any() and w[around].sum() >= 0.5 * w[near].sum():
                near = around
        wc = w[near]
        total = float(wc.sum())
        wn = wc / total
        mx, my = float(wn @ p[near, 0]), float(wn @ p[near, 1])
        mth = circular_mean(p[near, 2], wn)
        d = np.column_stack([p[near, 0] - mx, p[near, 1] - my,
                             (p[near, 2] - mth + np.pi) % (2 * np.pi) - np.pi])
        cov = (d * wn[:, None]).T @ d
        return ClusterEstimate(Pose2D(mx, my, mth), cov, total)
