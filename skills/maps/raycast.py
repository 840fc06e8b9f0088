"""Vectorised 2D ray casting.

:func:`cast_rays` intersects rays exactly with line segments (a simulated
laser for test doubles, expected ranges for benchmarks); :func:`march_rays`
steps rays through an occupancy grid (cheap expected ranges for the
localiser's fit score).
"""
from __future__ import annotations

import numpy as np

from .grid import GridSpec


def cast_rays(origins: np.ndarray, angles: np.ndarray, segments: np.ndarray,
              max_range: float) -> np.ndarray:
    """Range along each ray to the first segment, ``inf`` beyond ``max_range``.

    ``origins`` (R, 2) or (2,), ``angles`` (R,) field-frame radians,
    ``segments`` (S, 4) as x0, y0, x1, y1.
    """
    origins = np.broadcast_to(np.asarray(origins, float), (len(angles), 2))
    if len(segments) == 0:
        return np.full(len(angles), np.inf)
    d = np.stack([np.cos(angles), np.sin(angles)], axis=1)          # (R, 2)
    p0 = segments[:, :2]
    e = segments[:, 2:] - p0                                        # (S, 2)
    w = p0[None, :, :] - origins[:, None, :]                        # (R, S, 2)
    denom = d[:, None, 0] * e[None, :, 1] - d[:, None, 1] * e[None, :, 0]   # cross(d, e)
    with np.errstate(divide="ignore", invalid="ignore"):
        t = (w[..., 0] * e[None, :, 1] - w[..., 1] * e[None, :, 0]) / denom   # along the ray
        u = (w[..., 0] * d[:, None, 1] - w[..., 1] * d[:, None, 0]) / denom   # along the segment
    hit = (np.abs(denom) > 1e-12) & (t > 1e-9) & (u >= 0.0) & (u <= 1.0)
    t = np.where(hit, t, np.inf)
    r = t.min(axis=1)
    r[r > max_range] = np.inf
    return r


def march_rays(spec: GridSpec, occupied: np.ndarray, origin: tuple[float, float],
               angles: np.ndarray, max_range: float) -> np.ndarray:
    """Range to the first occupied cell along each ray, sampled every half
    cell; ``inf`` when none is met within ``max_range`` or the ray leaves
    the grid."""
    step = spec.resolution * 0.5
    t = np.arange(step, max_range + step, step)                     # (K,)
    xs = origin[0] + np.cos(angles)[:, None] * t[None, :]
    ys = origin[1] + np.sin(angles)[:, None] * t[None, :]
    row, col = spec.cell_of(xs, ys)
    inside = spec.inside(row, col)
    occ = np.zeros(xs.shape, dtype=bool)
    occ[inside] = occupied[row[inside], col[inside]]
    first = np.argmax(occ, axis=1)
    r = t[first]
    r[~occ.any(axis=1)] = np.inf
    return r
