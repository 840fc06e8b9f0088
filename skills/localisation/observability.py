"""Which directions a scan pins the robot's position in.

A beam that ends on a mapped wall or station face tells the robot's
distance to that surface along the surface's normal and nothing along the
surface.  Summed over the beams, ``J = sum n n^T`` (a 2 x 2 matrix over x, y)
counts the beams' worth of evidence in each direction: its small eigenvalue
is how many beams constrain the weakest direction, its eigenvector that
direction.  A robot beside a long wall whose laser does not reach the
walls at either end (the URG-04LX reaches 5.6 m, the 2016 field is 12 m
long, and stations are not mapped before exploration) has ``J`` of rank one:
the scan fits every pose along the wall equally, and a particle filter's
cloud drifts along it with nothing to hold it (0.8 m off in 11 s of
turning, seen on the seed-1 field).
"""
from __future__ import annotations

import numpy as np

from rll_bt.backend import Pose2D


def beam_normals(pose: Pose2D, ranges: np.ndarray, angles: np.ndarray, mount: Pose2D,
                 segments: np.ndarray, tolerance: float) -> np.ndarray:
    """Unit normals (K, 2) of the mapped segments (S, 4) that the beams seen
    from ``pose`` end on (within ``tolerance`` metres); beams ending nowhere
    mapped (an unmapped station, a robot) give none."""
    if len(ranges) == 0 or len(segments) == 0:
        return np.zeros((0, 2))
    origin = pose.compose(mount)
    a = angles + origin.theta
    ends = np.column_stack([origin.x + ranges * np.cos(a), origin.y + ranges * np.sin(a)])   # (M, 2)
    p0, d = segments[:, :2], segments[:, 2:] - segments[:, :2]                               # (S, 2)
    length2 = np.maximum((d * d).sum(axis=1), 1e-12)
    rel = ends[:, None, :] - p0[None, :, :]                                                  # (M, S, 2)
    t = np.clip((rel * d[None]).sum(axis=2) / length2, 0.0, 1.0)
    gap = np.hypot(*(rel - t[..., None] * d[None]).transpose(2, 0, 1))                       # (M, S)
    nearest = gap.argmin(axis=1)
    on = gap[np.arange(len(ends)), nearest] <= tolerance
    along = d[nearest[on]] / np.sqrt(length2[nearest[on]])[:, None]
    return np.column_stack([-along[:, 1], along[:, 0]])


def weakest_direction(normals: np.ndarray) -> tuple[float, np.ndarray]:
    """(beams' worth of evidence along the weakest direction, that unit direction (2,))."""
    if len(normals) == 0:
        return 0.0, np.array([1.0, 0.0])
    values, vectors = np.linalg.eigh(normals.T @ normals)
    return float(values[0]), vectors[:, 0]
