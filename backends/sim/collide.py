"""Planar collision geometry: oriented boxes and circles in the field frame.

Robots move kinematically, so blocking and contact are decided here in 2D
(a few microseconds per check) rather than by the physics engine.  Units are
metres and radians.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field


@dataclass(frozen=True)
class Box2D:
    """A rectangle centred at (cx, cy), rotated by ``theta``, with half
    extents ``hx`` along its own x axis and ``hy`` along its y axis."""
    cx: float
    cy: float
    theta: float
    hx: float
    hy: float
    _c: float = field(init=False, repr=False, compare=False)
    _s: float = field(init=False, repr=False, compare=False)

    def __post_init__(self):
        object.__setattr__(self, "_c", math.cos(self.theta))
        object.__setattr__(self, "_s", math.sin(self.theta))

    @classmethod
    def from_rect(cls, x_min: float, y_min: float, x_max: float, y_max: float) -> Box2D:
        return cls((x_min + x_max) / 2.0, (y_min + y_max) / 2.0, 0.0,
                   (x_max - x_min) / 2.0, (y_max - y_min) / 2.0)

    @property
    def bound_radius(self) -> float:
        return math.hypot(self.hx, self.hy)

    def to_local(self, x: float, y: float) -> tuple[float, float]:
        dx, dy = x - self.cx, y - self.cy
        return self._c * dx + self._s * dy, -self._s * dx + self._c * dy

    def to_world(self, lx: float, ly: float) -> tuple[float, float]:
        return self.cx + self._c * lx - self._s * ly, self.cy + self._s * lx + self._c * ly

    def sdf(self, x: float, y: float) -> float:
        """Signed distance from a point to the box edge (negative inside)."""
        lx, ly = self.to_local(x, y)
        qx, qy = abs(lx) - self.hx, abs(ly) - self.hy
        outside = math.hypot(max(qx, 0.0), max(qy, 0.0))
        return outside + min(max(qx, qy), 0.0)

    def corners(self) -> list[tuple[float, float]]:
        return [self.to_world(sx * self.hx, sy * self.hy)
                for sx, sy in ((1, 1), (-1, 1), (-1, -1), (1, -1))]

    def half_extents_world(self) -> tuple[float, float]:
        """Half width and height of the axis-aligned box around this one."""
        c, s = abs(self._c), abs(self._s)
        return c * self.hx + s * self.hy, s * self.hx + c * self.hy

    def axes(self) -> tuple[tuple[float, float], tuple[float, float]]:
        return (self._c, self._s), (-self._s, self._c)


def circle_clearance(box: Box2D, x: float, y: float, r: float) -> float:
    """Gap between a circle and a box (negative: they overlap by that much)."""
    return box.sdf(x, y) - r


def boxes_overlap(a: Box2D, b: Box2D) -> bool:
    """Separating-axis test for two rectangles."""
    for axis in (*a.axes(), *b.axes()):
        pa = [c[0] * axis[0] + c[1] * axis[1] for c in a.corners()]
        pb = [c[0] * axis[0] + c[1] * axis[1] for c in b.corners()]
        if max(pa) < min(pb) or max(pb) < min(pa):
            return False
    return True


def box_distance(a: Box2D, b: Box2D) -> float:
    """Smallest gap between two rectangles (0 when they touch or overlap)."""
    if boxes_overlap(a, b):
        return 0.0
    gaps = [b.sdf(x, y) for x, y in a.corners()] + [a.sdf(x, y) for x, y in b.corners()]
    return max(0.0, min(gaps))


class ObstacleGrid:
    """Static boxes bucketed into square cells, so a query returns only the
    boxes that may lie within ``pad`` metres of a point."""

    def __init__(self, items: list[tuple[str, Box2D]], cell: float = 1.0, pad: float = 0.5):
        self.cell, self.pad = cell, pad
        self._cells: dict[tuple[int, int], list[tuple[str, Box2D]]] = {}
        for name, box in items:
            ex, ey = box.half_extents_world()
            x0, x1 = self._index(box.cx - ex - pad), self._index(box.cx + ex + pad)
            y0, y1 = self._index(box.cy - ey - pad), self._index(box.cy + ey + pad)
            for i in range(x0, x1 + 1):
                for j in range(y0, y1 + 1):
                    self._cells.setdefault((i, j), []).append((name, box))

    def _index(self, v: float) -> int:
        return int(math.floor(v / self.cell))

    def near(self, x: float, y: float) -> list[tuple[str, Box2D]]:
        return self._cells.get((self._index(x), self._index(y)), [])
