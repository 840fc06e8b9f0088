"""KLD sampling (Fox 2003): how many particles a posterior needs.

With k histogram bins occupied, n = (k - 1) / (2 eps) * (1 - 2/(9(k-1)) +
sqrt(2/(9(k-1))) * z)^3 particles keep the Kullback-Leibler error below
``eps`` with probability given by the normal quantile ``z``.
"""
from __future__ import annotations

import numpy as np


def kld_count(k, epsilon: float = 0.05, z: float = 2.326):
    """Particles needed for ``k`` occupied bins (k may be an array)."""
    k = np.asarray(k, dtype=float)
    km1 = np.maximum(k - 1.0, 1.0)
    a = 2.0 / (9.0 * km1)
    n = km1 / (2.0 * epsilon) * (1.0 - a + np.sqrt(a) * z) ** 3
    return np.where(k <= 1, 1.0, n)


def bin_keys(particles: np.ndarray, xy_size: float = 0.5, theta_size: float = np.radians(10.0)) -> np.ndarray:
    """One integer per particle naming its (x, y, theta) histogram bin."""
    ix = np.floor(particles[:, 0] / xy_size).astype(np.int64) + (1 << 20)
    iy = np.floor(particles[:, 1] / xy_size).astype(np.int64) + (1 << 20)
    it = np.floor((particles[:, 2] + np.pi) / theta_size).astype(np.int64)
    return (ix << 42) | (iy << 21) | it


def kld_prefix_length(keys: np.ndarray, n_min: int, n_max: int, epsilon: float, z: float) -> int:
    """How many of the (randomly ordered) draws ``keys`` to keep: the first
    prefix whose length reaches the KLD count of the bins it occupies,
    clamped to [n_min, n_max]."""
    keys = keys[:n_max]
    _, first = np.unique(keys, return_index=True)
    new_bin = np.zeros(len(keys), dtype=bool)
    new_bin[first] = True
    k = np.cumsum(new_bin)
    need = kld_count(k, epsilon, z)
    lengths = np.arange(1, len(keys) + 1)
    ok = np.nonzero((lengths >= need) & (lengths >= n_min))[0]
    n = int(ok[0]) + 1 if len(ok) else len(keys)
    return max(min(n, n_max), min(n_min, len(keys)))
