"""Workpieces: a base colour, a list of rings and an optional cap, drawn as
stacked cylinders.  Colours use the refbox enum names of
:mod:`rll_bt.rules` (``BASE_RED``, ``RING_BLUE``, ``CAP_GREY``, ...).

Where a workpiece is lives in :class:`WorkpieceStore`: at a station slot, in
a robot's gripper, or on the floor.  Heights in metres above the floor.
"""
from __future__ import annotations

from dataclasses import dataclass, replace

from rll_bt.rules import BASE_COLORS, CAP_COLORS, RING_COLORS, WORKPIECE

from .bullet import IDENTITY, Part, ShapeCache, multibody, pybullet

RGBA = {
    "BASE_RED": (0.80, 0.08, 0.08, 1.0), "BASE_BLACK": (0.08, 0.08, 0.08, 1.0),
    "BASE_SILVER": (0.78, 0.78, 0.82, 1.0),
    "RING_BLUE": (0.10, 0.30, 0.95, 1.0), "RING_GREEN": (0.10, 0.70, 0.20, 1.0),
    "RING_ORANGE": (1.00, 0.50, 0.00, 1.0), "RING_YELLOW": (1.00, 0.90, 0.10, 1.0),
    "CAP_BLACK": (0.05, 0.05, 0.05, 1.0), "CAP_GREY": (0.50, 0.50, 0.52, 1.0),
}
RING_RADIUS = WORKPIECE.radius + 0.004


@dataclass(frozen=True)
class Workpiece:
    """A product in the making.  ``id`` stays the same while rings and caps
    are added or removed."""
    id: int
    base: str
    rings: tuple[str, ...] = ()
    cap: str | None = None

    def __post_init__(self):
        if self.base not in BASE_COLORS:
            raise ValueError(f"unknown base colour {self.base!r} (known: {', '.join(BASE_COLORS)})")
        for r in self.rings:
            if r not in RING_COLORS:
                raise ValueError(f"unknown ring colour {r!r} (known: {', '.join(RING_COLORS)})")
        if self.cap is not None and self.cap not in CAP_COLORS:
            raise ValueError(f"unknown cap colour {self.cap!r} (known: {', '.join(CAP_COLORS)})")
        if len(self.rings) > 3:
            raise ValueError(f"a workpiece carries at most 3 rings, not {len(self.rings)}")

    def with_ring(self, color: str) -> Workpiece:
        return replace(self, rings=self.rings + (color,))

    def with_cap(self, color: str | None) -> Workpiece:
        return replace(self, cap=color)

    @property
    def height(self) -> float:
        w = WORKPIECE
        return w.base_height + w.ring_height * len(self.rings) + (w.cap_height if self.cap else 0.0)


@dataclass(frozen=True)
class Location:
    """``kind`` is "slot" (machine, slot), "robot" (robot key) or "floor" (x, y)."""
    kind: str
    machine: str | None = None
    slot: str | None = None
    robot: tuple[str, int] | None = None
    xy: tuple[float, float] | None = None


def build_body(cid: int, shapes: ShapeCache, wp: Workpiece, position, orientation=IDENTITY) -> int:
    """A visual-only body for ``wp``; ``position`` is the centre of the
    bottom face of the base."""
    w = WORKPIECE
    base = shapes.cylinder(w.radius, w.base_height, RGBA[wp.base])
    parts, z = [], w.base_height
    for ring in wp.rings:
        parts.append(Part(shapes.cylinder(RING_RADIUS, w.ring_height, RGBA[ring]),
                          (0.0, 0.0, z + w.ring_height / 2.0 - w.base_height / 2.0)))
        z += w.ring_height
    if wp.cap:
        parts.append(Part(shapes.cylinder(w.radius, w.cap_height, RGBA[wp.cap]),
                          (0.0, 0.0, z + w.cap_height / 2.0 - w.base_height / 2.0)))
    x, y, zb = position
    return multibody(cid, base, parts, position=(x, y, zb + w.base_height / 2.0),
                     orientation=orientation, mass=0.01)


def move_body(cid: int, body: int, position) -> None:
    """Put a workpiece body with its bottom centre at ``position``."""
    x, y, z = position
    pybullet().resetBasePositionAndOrientation(body, [x, y, z + WORKPIECE.base_height / 2.0],
                                               list(IDENTITY), physicsClientId=cid)


def remove_body(cid: int, body: int) -> None:
    pybullet().removeBody(body, physicsClientId=cid)
