"""Navigation goals: a pose, a zone (its centre, or the nearest free spot
inside it) or a station side (a pose in front of an input or output face).

Every goal resolves against a :class:`~skills.context.SkillContext` to a
field pose and whether its heading matters; a station side needs the
station's pose from ``ctx.machines``.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from rll_bt.backend import Pose2D
from rll_bt.rules import MPS, MpsGeometry

from ..errors import SkillError, SkillFailure

SIDES = ("INPUT", "OUTPUT")


def side_sign(side: str) -> float:
    """+1 for the input face (machine x = +depth/2), -1 for the output face."""
    side = side.upper()
    if side not in SIDES:
        raise ValueError(f"side must be INPUT or OUTPUT, not {side!r}")
    return 1.0 if side == "INPUT" else -1.0


def target_lateral(target: str, mps: MpsGeometry = MPS) -> float:
    """Machine-frame y (m) of a place on a face: ``conveyor``, ``slide``,
    ``shelf0``/``shelf1``/``shelf2`` (the cap station's shelf slots)."""
    t = target.lower()
    if t == "conveyor":
        return mps.belt_offset_y
    if t == "slide":
        return mps.slide_y
    if t.startswith("shelf") and t[5:].isdigit() and int(t[5:]) < len(mps.shelf_y):
        return mps.shelf_y[int(t[5:])]
    raise ValueError(f"unknown place {target!r} (conveyor, slide, shelf0..shelf{len(mps.shelf_y) - 1})")


def approach_pose(machine: Pose2D, side: str, distance: float, lateral: float | None = None,
                  mps: MpsGeometry = MPS) -> Pose2D:
    """The robot pose facing ``side`` of a station, its centre ``distance``
    metres from the face, on the line of machine-frame y = ``lateral``
    (default: the conveyor's centre line)."""
    sx = side_sign(side)
    y = mps.belt_offset_y if lateral is None else lateral
    local = Pose2D(sx * (mps.depth / 2.0 + distance), y, math.pi if sx > 0 else 0.0)
    return machine.compose(local)


def standing_clearance(ctx) -> float:
    """Clearance (m) the robot needs at a goal: what the planner's costmap
    keeps free (radius plus padding), so goal and path agree."""
    return ctx.robot.radius + ctx.settings.plan_padding + 0.01


def nearest_fit(field_map, x: float, y: float, need: float, reach: float = 0.5,
                step: float = 0.01) -> tuple[float, float] | None:
    """The point nearest to (x, y), within ``reach`` metres, whose exact
    clearance from the map's walls and stations is at least ``need`` (on a
    ``step`` lattice round the point); None when there is none."""
    k = int(math.ceil(reach / step))
    off = np.arange(-k, k + 1) * step
    dx, dy = np.meshgrid(off, off)
    r = np.hypot(dx, dy).ravel()
    inside = r <= reach + 1e-9
    px, py = x + dx.ravel()[inside], y + dy.ravel()[inside]
    r = r[inside]
    ok = field_map.clearance(px, py) >= need
    if not ok.any():
        return None
    i = int(np.argmin(np.where(ok, r, np.inf)))
    return float(px[i]), float(py[i])


def feasible_distance(ctx, machine_pose: Pose2D, side: str, distance: float, lateral: float,
                      minimum: float = 0.40) -> float | None:
    """The largest distance from the face, at most ``distance`` and at least
    ``minimum``, where the robot fits in front of the station (walls and
    other stations of the map leave room, and the station itself: never
    closer to its face than the planner's clearance); None when none does."""
    mps = ctx.profile.mps
    need = standing_clearance(ctx)
    ds = np.arange(distance, minimum - 1e-9, -0.02)
    if len(ds) == 0:
        return None
    poses = [approach_pose(machine_pose, side, float(d), lateral, mps) for d in ds]
    # the exact distance to the map's segments: a 5-cm cell's value holds
    # only at its centre, up to 3.5 cm off elsewhere, enough to shut a
    # window of a few centimetres in front of a face
    clear = ctx.map.clearance(np.array([p.x for p in poses]), np.array([p.y for p in poses]))
    ok = np.nonzero(clear >= need)[0]
    return float(ds[ok[0]]) if len(ok) else None


@dataclass(frozen=True)
class PoseGoal:
    pose: Pose2D
    heading: bool = True           # whether the final heading matters

    def resolve(self, ctx) -> tuple[Pose2D, bool]:
        return self.pose, self.heading

    def describe(self) -> str:
        p = self.pose
        return f"pose ({p.x:.2f}, {p.y:.2f}, {math.degrees(p.theta):.0f} deg)"


@dataclass(frozen=True)
class ZoneGoal:
    """The zone's centre, or the free spot inside the zone nearest to it
    (a station may stand at the centre).  ``heading`` None: any."""
    zone: int
    heading: float | None = None

    def resolve(self, ctx) -> tuple[Pose2D, bool]:
        prof = ctx.profile
        try:
            rect = prof.zones.bounds(self.zone)
        except ValueError as exc:
            raise SkillFailure(SkillError.INVALID_TASK, str(exc)) from None
        cx, cy = rect.centre
        cm = ctx.costmap
        if bool(cm.is_free(cx, cy)):
            x, y = cx, cy
        else:
            xs, ys = cm.spec.centres()
            inside = (xs >= rect.x_min) & (xs <= rect.x_max) & (ys >= rect.y_min) & (ys <= rect.y_max)
            lethal, _ = cm.grids()
            ok = inside & ~lethal
            if not ok.any():
                raise SkillFailure(SkillError.INVALID_TASK, f"zone {prof.zone_name(self.zone)} has no free spot")
            d = np.where(ok, np.hypot(xs - cx, ys - cy), np.inf)
            r, c = np.unravel_index(int(np.argmin(d)), d.shape)
            x, y = float(xs[r, c]), float(ys[r, c])
        theta = self.heading if self.heading is not None else 0.0
        return Pose2D(x, y, theta), self.heading is not None

    def describe(self) -> str:
        return f"zone {self.zone}"


@dataclass(frozen=True)
class StationSideGoal:
    """In front of ``side`` of ``machine``, facing it, ``distance`` metres
    from the face (less where a wall or another station leaves less room,
    down to ``minimum``), aligned with ``place`` (conveyor, slide, shelfN)."""
    machine: str
    side: str
    distance: float = 0.6
    place: str = "conveyor"
    minimum: float = 0.40

    def resolve(self, ctx) -> tuple[Pose2D, bool]:
        pose = ctx.machines.get(self.machine)
        if pose is None:
            raise SkillFailure(SkillError.MACHINE_NOT_FOUND, f"the pose of {self.machine} is not known")
        mps = ctx.profile.mps
        try:
            lateral = target_lateral(self.place, mps)
            side_sign(self.side)
        except ValueError as exc:
            raise SkillFailure(SkillError.INVALID_TASK, str(exc)) from None
        d = feasible_distance(ctx, pose, self.side, self.distance, lateral, self.minimum)
        if d is None:
            raise SkillFailure(SkillError.NAVIGATION_FAILED,
                               f"no room for the robot in front of {self.describe()}")
        return approach_pose(pose, self.side, d, lateral, mps), True

    def describe(self) -> str:
        return f"{self.machine} {self.side.lower()} ({self.place})"
