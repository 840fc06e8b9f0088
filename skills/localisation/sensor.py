"""Likelihood-field laser model over a precomputed distance grid.

For a beam endpoint at distance d from the nearest wall or obstacle of the
map, p = z_hit * exp(-d^2 / (2 sigma_hit^2)) + z_rand / range_max (AMCL's
unnormalised form).  ``log p`` is precomputed per cell from the map's
distance transform, so weighing N particles by M beams is one gather of
N x M cells.  Readings at or beyond ``range_max`` are dropped before they
get here.
"""
from __future__ import annotations

import math

import numpy as np

from ..maps import FieldMap


class LikelihoodField:
    def __init__(self, field_map: FieldMap, resolution: float = 0.05, sigma_hit: float = 0.08,
                 z_hit: float = 0.9, z_rand: float = 0.1, range_max: float = 10.0):
        self.map = field_map
        self.resolution = resolution
        self.sigma_hit = sigma_hit
        self.z_hit = z_hit
        self.z_rand = z_rand
        self.range_max = range_max
        self._version = -1
        self._build()

    @property
    def floor(self) -> float:
        """log p of an endpoint far from everything (or off the map)."""
        return math.log(self.z_rand / self.range_max)

    def _build(self) -> None:
        dist = self.map.distance(self.resolution)
        self.spec = dist.spec
        d = dist.distance.astype(np.float64)
        p = self.z_hit * np.exp(-0.5 * (d / self.sigma_hit) ** 2) + self.z_rand / self.range_max
        self.log_p = np.log(p).astype(np.float32).ravel()
        self._version = self.map.version

    def refresh(self) -> None:
        """Rebuild when the map changed (a station was added)."""
        if self.map.version != self._version:
            self._build()

    def endpoints(self, particles: np.ndarray, beams: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Field x, y (N, M) of beam endpoints ``beams`` (M, 2, robot frame)
        for every particle (N, 3)."""
        c, s = np.cos(particles[:, 2:3]), np.sin(particles[:, 2:3])
        bx, by = beams[None, :, 0], beams[None, :, 1]
        return particles[:, 0:1] + c * bx - s * by, particles[:, 1:2] + s * bx + c * by

    def log_likelihood(self, particles: np.ndarray, beams: np.ndarray) -> np.ndarray:
        """(N, M) log p of each beam for each particle."""
        ex, ey = self.endpoints(particles, beams)
        spec = self.spec
        col = ((ex - spec.x0) * (1.0 / spec.resolution)).astype(np.int32)
        row = ((ey - spec.y0) * (1.0 / spec.resolution)).astype(np.int32)
        ok = (row >= 0) & (row < spec.rows) & (col >= 0) & (col < spec.cols)
        flat = np.where(ok, row * spec.cols + col, 0)
        lp = self.log_p[flat]
        if not ok.all():
            lp = np.where(ok, lp, np.float32(self.floor))
        return lp
