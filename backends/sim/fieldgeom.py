"""Pure geometry of a field built from a rules profile: walls, floor, robot
start poses and station footprints.  Shared by the world, the layout
generator and the top-view drawing.  Field frame, metres, radians.
"""
from __future__ import annotations

import math

from rll_bt.backend import Pose2D
from rll_bt.rules import CYAN, Profile, Rect

from .collide import Box2D

WALL_THICKNESS = 0.05
WALL_HEIGHT = 0.5
FLOOR_MARGIN = 1.0


def _subtract(span: tuple[float, float], holes: list[tuple[float, float]]) -> list[tuple[float, float]]:
    """Pieces of the interval ``span`` not covered by ``holes``."""
    pieces = [span]
    for h0, h1 in holes:
        out = []
        for a, b in pieces:
            if h1 <= a or h0 >= b:
                out.append((a, b))
                continue
            if h0 > a:
                out.append((a, h0))
            if h1 < b:
                out.append((h1, b))
        pieces = out
    return [(a, b) for a, b in pieces if b - a > 1e-6]


def walls(profile: Profile, thickness: float = WALL_THICKNESS) -> list[Rect]:
    """Wall rectangles just outside the field boundary.

    Insertion areas inside the field (2017+) are enclosed by the outer wall;
    an insertion area outside the field (2016, below y = 0) opens the field
    wall over its width and is walled on its three other sides."""
    f, t = profile.field, thickness
    outside = [r for r in profile.insertion.values() if r.y_max <= f.y_min + 1e-9]
    out = [Rect(f.x_min - t, f.y_max, f.x_max + t, f.y_max + t),     # far wall
           Rect(f.x_min - t, f.y_min - t, f.x_min, f.y_max),         # left side
           Rect(f.x_max, f.y_min - t, f.x_max + t, f.y_max)]         # right side
    for a, b in _subtract((f.x_min - t, f.x_max + t), [(r.x_min, r.x_max) for r in outside]):
        out.append(Rect(a, f.y_min - t, b, f.y_min))
    for r in outside:
        out.append(Rect(r.x_min - t, r.y_min - t, r.x_max + t, r.y_min))   # outer end
        out.append(Rect(r.x_min - t, r.y_min, r.x_min, f.y_min))           # sides
        out.append(Rect(r.x_max, r.y_min, r.x_max + t, f.y_min))
    return out


def floor_rect(profile: Profile, margin: float = FLOOR_MARGIN) -> Rect:
    """The finite floor: field and insertion areas plus a margin."""
    rects = [profile.field, *profile.insertion.values()]
    return Rect(min(r.x_min for r in rects) - margin, min(r.y_min for r in rects) - margin,
                max(r.x_max for r in rects) + margin, max(r.y_max for r in rects) + margin)


def start_pose(profile: Profile, team: str, number: int) -> Pose2D:
    """Where robot ``number`` (1..) of ``team`` starts: spread over the team's
    insertion area (three lanes, then repeating), facing into the field (+y).
    Magenta mirrors cyan (x -> -x)."""
    if number < 1:
        raise ValueError(f"robot numbers start at 1, not {number}")
    area = profile.insertion[CYAN]
    k = (number - 1) % 3
    x = area.x_min + (k + 0.5) * (area.x_max - area.x_min) / 3.0
    y = (area.y_min + area.y_max) / 2.0
    if team != CYAN:
        x, y = profile.mirror_point(x, y)
    return Pose2D(x, y, math.pi / 2.0)


def entry_point(profile: Profile, team: str, number: int) -> tuple[float, float]:
    """A point in front of the start pose, just inside the field, that must
    stay free of stations so the robot can drive in."""
    s = start_pose(profile, team, number)
    f = profile.field
    return s.x, max(s.y, f.y_min) + 0.45


def footprint(profile: Profile, pose: Pose2D) -> Box2D:
    """The station's footprint (0.35 along its x, 0.7 along its y) at ``pose``."""
    m = profile.mps
    return Box2D(pose.x, pose.y, pose.theta, m.depth / 2.0, m.width / 2.0)


def approach_points(profile: Profile, pose: Pose2D, distance: float = 0.45) -> dict[str, tuple[float, float]]:
    """Points ``distance`` in front of the input (+x) and output (-x) faces."""
    d = profile.mps.depth / 2.0 + distance
    c, s = math.cos(pose.theta), math.sin(pose.theta)
    return {"input": (pose.x + d * c, pose.y + d * s), "output": (pose.x - d * c, pose.y - d * s)}
