"""Other robots as the laser sees them: points the map does not explain,
and the room a robot at a station will need when it leaves.

Nothing tells a robot where the other team's robots are (nor, to its
skills, where its own team's are): what the map of walls and stations does
not explain in a scan may be a robot.  A robot standing at a station's face
(lining up, docked, waiting at it) backs straight off it when it is done,
blind, since its laser looks at the station; so the others keep out of the
strip behind it: :func:`station_zones` adds, to every unexplained point
near a station, copies moved outward from the station by up to
``back_off`` metres.  A navigation treats those like the robot itself: it
does not pass through that strip, plans around it, and does not drive to a
goal inside it - it waits until the robot at the station has left (the
robot that was there first has the right of way).

Units: metres, the field frame.
"""
from __future__ import annotations

import numpy as np

#: a point closer than this (m) to a wall or station in the map is that wall or station
EXPLAINED = 0.1
#: a robot at a station: unexplained points this close (m) to a station's edge
AT_STATION = 0.5
#: how far a robot at a station backs off (m): the settings' back-off and its radius' share of slack
BACK_OFF = 0.4


def unexplained(ctx, points: np.ndarray) -> np.ndarray:
    """Mask of field points (K, 2) farther than :data:`EXPLAINED` from every
    wall and station of the map."""
    if len(points) == 0:
        return np.zeros(0, dtype=bool)
    dist = ctx.map.distance(ctx.costmap.resolution).lookup(points[:, 0], points[:, 1])
    return dist > EXPLAINED


def station_zones(ctx, points: np.ndarray, back_off: float = BACK_OFF, step: float = 0.1) -> np.ndarray:
    """Field points (M, 2) that stand for the strip a robot at a station
    needs to back off: each of ``points`` (unexplained field points) within
    :data:`AT_STATION` of a station's edge, moved outward from that edge
    (along the line from its nearest point on the edge) by ``step``,
    2 ``step``, ... up to ``back_off``.  Empty without stations or such points."""
    segs = ctx.map.obstacle_segments()
    if len(points) == 0 or len(segs) == 0:
        return np.zeros((0, 2))
    a, ab = segs[:, :2], segs[:, 2:] - segs[:, :2]
    len2 = np.maximum((ab * ab).sum(axis=1), 1e-12)
    q = points[:, None, :] - a[None, :, :]
    t = np.clip((q * ab[None, :, :]).sum(axis=2) / len2[None, :], 0.0, 1.0)
    near = a[None, :, :] + t[:, :, None] * ab[None, :, :]
    off = points[:, None, :] - near
    d = np.hypot(off[:, :, 0], off[:, :, 1])
    k = np.argmin(d, axis=1)
    rows = np.arange(len(points))
    dk = d[rows, k]
    keep = (dk <= AT_STATION) & (dk > 1e-6)
    if not keep.any():
        return np.zeros((0, 2))
    out = off[rows, k][keep] / dk[keep][:, None]
    base = points[keep]
    shifts = np.arange(step, back_off + 1e-9, step)
    return (base[None, :, :] + shifts[:, None, None] * out[None, :, :]).reshape(-1, 2)


def occupied(points: np.ndarray, x: float, y: float, radius: float) -> bool:
    """Whether any of the field points (K, 2) lies within ``radius`` of (x, y)."""
    if len(points) == 0:
        return False
    return bool((np.hypot(points[:, 0] - x, points[:, 1] - y) < radius).any())
