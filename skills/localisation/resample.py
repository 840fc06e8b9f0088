"""Resampling with filterpy's systematic resampler, made deterministic.

``filterpy.monte_carlo.systematic_resample`` draws its one random offset
from numpy's *global* generator.  :func:`systematic_indices` seeds the
global generator from the filter's own ``Generator`` for that call and
restores the previous global state afterwards, so a filter is reproducible
for its seed and other users of ``np.random`` are not disturbed.
"""
from __future__ import annotations

import threading

import numpy as np
from filterpy.monte_carlo import systematic_resample

_LOCK = threading.Lock()


def systematic_indices(weights: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    """len(weights) indices drawn by systematic resampling; ``weights`` sum to 1."""
    w = np.asarray(weights, dtype=float)
    seed = int(rng.integers(0, 2**32 - 1))
    with _LOCK:
        saved = np.random.get_state()
        np.random.seed(seed)
        try:
            idx = systematic_resample(w)
        except IndexError:
            # the cumulative sum fell short of the last position by rounding
            cum = np.cumsum(w)
            cum[-1] = 1.0
            positions = (np.random.random() + np.arange(len(w))) / len(w)
            idx = np.searchsorted(cum, positions, side="right")
        finally:
            np.random.set_state(saved)
    return np.minimum(np.asarray(idx, dtype=np.int64), len(w) - 1)


def draw(weights: np.ndarray, count: int, rng: np.random.Generator) -> np.ndarray:
    """``count`` indices in random order: one systematic pass over the
    weights repeated ``k`` times (each copy weighing 1/k), enough for
    ``count`` draws, then shuffled (the order matters for KLD, which keeps a
    prefix)."""
    n = len(weights)
    k = max(1, -(-count // n))
    tiled = np.tile(np.asarray(weights, dtype=float) / k, k)
    idx = systematic_indices(tiled, rng) % n
    return idx[rng.permutation(len(idx))[:count]]
