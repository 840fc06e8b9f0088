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

import math

import numpy as np

#: a point closer than this (m) to a wall or station in the map is that wall or station
EXPLAINED = 0.1
#: a robot at a station: unexplained points this close (m) to a station's edge
AT_STATION = 0.5
#: how far a robot at a station backs off (m): the settings' back-off and its radius' share of slack
BACK_OFF = 0.4
#: how far (m) and how much turned (rad) a station may stand from where the map has it
MAP_SLACK, MAP_TURN = 0.3, math.radians(12.0)
#: points within this (m) of a station's outline fitted to them lie on its face ...
FIT = 0.025
#: ... when they run this far (m) along one edge: a robot's round side never does
RUN = 0.3


def unexplained(ctx, points: np.ndarray) -> np.ndarray:
    """Mask of field points (K, 2) farther than :data:`EXPLAINED` from every
    wall and station of the map, and not on a station's face where it really
    stands (:func:`misplaced_station`)."""
    if len(points) == 0:
        return np.zeros(0, dtype=bool)
    dist = ctx.map.distance(ctx.costmap.resolution).lookup(points[:, 0], points[:, 1])
    out = dist > EXPLAINED
    for poly in ctx.map.obstacles.values():
        cand = points[out]
        lo, hi = poly.min(axis=0) - MAP_SLACK, poly.max(axis=0) + MAP_SLACK
        if len(cand) and np.all((cand >= lo) & (cand <= hi), axis=1).any():
            out &= ~misplaced_station(poly, points)
    return out


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


def _edge_fit(poly: np.ndarray, points: np.ndarray):
    """Residuals (K,), edge index (K,) and position along it (K,) of ``points``
    against the nearest edge of the closed polygon ``poly`` (N, 2)."""
    a = poly
    ab = np.roll(poly, -1, axis=0) - poly
    len2 = np.maximum((ab * ab).sum(axis=1), 1e-12)
    q = points[:, None, :] - a[None, :, :]
    t = np.clip((q * ab[None]).sum(axis=2) / len2[None, :], 0.0, 1.0)
    off = q - t[:, :, None] * ab[None]
    d = np.hypot(off[..., 0], off[..., 1])
    k = np.argmin(d, axis=1)
    rows = np.arange(len(points))
    length = np.sqrt(len2[k])
    normal = np.stack([ab[k, 1], -ab[k, 0]], axis=1) / length[:, None]
    signed = (off[rows, k] * normal).sum(axis=1)
    return signed, normal, k, t[rows, k] * length


def misplaced_station(poly: np.ndarray, points: np.ndarray, iterations: int = 5) -> np.ndarray:
    """Mask of field ``points`` (K, 2) that lie on the face of a station mapped
    as ``poly`` (N, 2) but standing up to :data:`MAP_SLACK` m and :data:`MAP_TURN`
    away (a pose from exploration is that far off): its outline moved and turned to
    fit the points near it (point-to-line least squares, trimmed as it closes
    in), the points within :data:`FIT` of the fitted outline that run at least
    :data:`RUN` m along one edge.  A robot at the station keeps its round side
    unexplained; without such a run the mask is empty."""
    none = np.zeros(len(points), dtype=bool)
    if len(points) < 3:
        return none
    centre = poly.mean(axis=0)
    lo, hi = poly.min(axis=0) - MAP_SLACK, poly.max(axis=0) + MAP_SLACK
    box = np.all((points >= lo) & (points <= hi), axis=1)
    if box.sum() < 3:
        return none
    pts = points[box]
    signed, _n, _k, _s = _edge_fit(poly, pts)
    near = np.abs(signed) <= MAP_SLACK
    if near.sum() < 3:
        return none
    pts = pts[near]
    moved, shift, turn = poly, np.zeros(2), 0.0
    for gate in np.geomspace(MAP_SLACK, 2 * FIT, iterations):
        signed, normal, _k, _s = _edge_fit(moved, pts)
        use = np.abs(signed) <= gate
        if use.sum() < 3:
            return none
        lever = pts[use] - (centre + shift)
        rot = normal[use, 1] * lever[:, 0] - normal[use, 0] * lever[:, 1]     # n . (perp(lever))
        jac = np.column_stack([normal[use], rot])           # moving the outline by d: n . d closes the gap
        rhs = signed[use]
        step = np.linalg.solve(jac.T @ jac + 1e-3 * np.eye(3), jac.T @ rhs)
        shift, turn = shift + step[:2], turn + step[2]
        if np.hypot(*shift) > MAP_SLACK or abs(turn) > MAP_TURN:
            return none
        c, s = math.cos(turn), math.sin(turn)
        moved = (poly - centre) @ np.array([[c, s], [-s, c]]) + centre + shift
    signed, _n, k, along = _edge_fit(moved, pts)
    on = np.abs(signed) <= FIT
    face = np.zeros(len(pts), dtype=bool)
    for edge in np.unique(k[on]):
        sel = on & (k == edge)
        if along[sel].max() - along[sel].min() >= RUN:
            face |= sel
    out = none.copy()
    idx = np.flatnonzero(box)[near]
    out[idx[face]] = True
    return out
