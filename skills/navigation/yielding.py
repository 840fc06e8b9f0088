"""Giving way to another robot: when a navigation steps aside, and where to.

Two robots can each stand in the other's only way: on either side of the gap
between two stations, one heading through it one way, the other the other
way (seed 1 of the process games: R1 above the gap between C-RS2 and M-RS2
heading down to C-RS2's slide, R3 below it heading up and over to C-BS;
each goal reachable only through that gap).  Each plans around the other,
finds no path and waits; both navigations fail after ``max_blocked``, the
team server sends the same two tasks again and the robots, still where they
stood, wait again until the end of the game.  Nothing tells a robot who the
other is or where it goes; so the rule is the same for every robot (of
either team) and needs only what the robot knows itself:

- a navigation blocked by another robot (laser points the map does not
  explain) that stands still, with no way round it, for :func:`yield_delay`
  seconds steps aside (the clock starts again whenever the other robot has
  moved 0.3 m: it may be stepping aside itself): ``yield_after`` plus
  ``yield_step`` per rank above 1 (the robot's number, so two robots of one
  team never step aside at once) plus a quarter step when its key (its
  position along a fixed oblique axis) is the greater of the two (so two
  robots of the same number, of two teams, mostly do not either).  Three
  quarters of a step are more than a robot takes to turn to its way aside
  (it looks before it leaves, up to 3 s) and to move 0.3 m; a navigation
  that gives up after less than :data:`PATIENT` seconds blocked (exploration's
  viewpoints, 8 s) does not step aside: it gives up soon anyway;
- it steps to :func:`yield_spot`: the free place within ``REACH`` metres of
  path that is at least ``MIN_GAP`` from the other robot and off the line
  the other robot came along through it (the other wants to go where this
  one stands), preferring open room (where the other can pass), a short way
  and, between alike places, the side of its own goal;
- it stands there ``yield_hold`` seconds, then plans its own way again; at
  most ``max_yields`` times per navigation (its blocked time starts again
  from 0 after a step aside, and the navigation's time limit grows by the
  time spent on it).

Units: metres, seconds, the field frame.
"""
from __future__ import annotations

import math

import numpy as np

#: metres from the other robot's centre a place to step aside to keeps at least
MIN_GAP = 0.85
#: metres off the other robot's line through this one (two radii and the planner's berth)
OFF_LINE = 0.65
#: path cost (weighted metres) to a place to step aside to, at most
REACH = 3.0
#: straight-line metres to a place to step aside to, at most; and at least (a real step)
FARTHEST, NEAREST = 1.6, 0.3
#: only another robot this close (m, to its nearest seen point) blocks this one
NEAR = 1.5
#: seconds blocked a navigation must be willing to wait for it to step aside at all
PATIENT = 10.0
#: the fixed oblique axis (rad) of the tie-break key, and the share of a step it adds
KEY_ANGLE, TIE = 1.0, 0.25


def yield_delay(settings, rank: int, me: tuple[float, float], other: tuple[float, float]) -> float:
    """Seconds blocked before a robot of number ``rank`` at ``me`` steps
    aside for the robot at ``other`` (see the module doc)."""
    c, s = math.cos(KEY_ANGLE), math.sin(KEY_ANGLE)
    tie = TIE if me[0] * c + me[1] * s > other[0] * c + other[1] * s else 0.0
    return settings.yield_after + settings.yield_step * (max(int(rank) - 1, 0) + tie)


def blocker(points: np.ndarray, here: tuple[float, float], radius: float) -> tuple[float, float] | None:
    """The centre of the nearest other robot: the nearest of ``points``
    (field points of other robots) within :data:`NEAR`, pushed back by
    ``radius`` along the line of sight (the laser sees its near side); None
    when none is that near."""
    got = disc_centre(points, here, radius)
    if got is None or got[1] > NEAR:
        return None
    return float(got[0][0]), float(got[0][1])


def disc_centre(points: np.ndarray, here, radius: float) -> tuple[np.ndarray, float] | None:
    """(centre, distance to it from ``here``'s nearest point of them) of the disc of
    ``radius`` whose nearest point to ``here`` is the nearest of ``points``: the point
    a laser at ``here`` sees of another robot lies on the line to its centre, so the
    centre does not move as the view changes.  None without points (or one at ``here``)."""
    if len(points) == 0:
        return None
    d = np.hypot(points[:, 0] - here[0], points[:, 1] - here[1])
    i = int(np.argmin(d))
    if d[i] < 1e-6:
        return None
    k = (d[i] + radius) / d[i]
    return np.array([here[0] + (points[i, 0] - here[0]) * k, here[1] + (points[i, 1] - here[1]) * k]), float(d[i])


def yield_spot(costmap, planner, here: tuple[float, float], other: tuple[float, float],
               goal: tuple[float, float]) -> tuple[float, float] | None:
    """A place to step aside to from ``here`` for the robot at ``other``
    (see the module doc), on the costmap as it is (the other robot's laser
    points in it), on the side of ``goal`` (its own) between alike places;
    None when there is none."""
    from .planner import NoPath
    try:
        cost = planner.costs_from(here, REACH)
    except NoPath:
        return None
    xs, ys = costmap.spec.centres()
    hx, hy = here
    bx, by = other
    ux, uy = hx - bx, hy - by
    n = math.hypot(ux, uy)
    if n < 1e-6:
        return None
    ux, uy = ux / n, uy / n
    lateral = np.abs((xs - bx) * uy - (ys - by) * ux)
    gap = np.hypot(xs - bx, ys - by)
    step = np.hypot(xs - hx, ys - hy)
    ok = np.isfinite(cost) & (gap >= MIN_GAP) & (lateral >= OFF_LINE) & (step >= NEAREST) & (step <= FARTHEST)
    if not ok.any():
        return None
    room = np.minimum(costmap.clearance(), 0.6)
    # between two alike places: the side of its own goal (the way back is shorter)
    side = np.sign((xs - bx) * uy - (ys - by) * ux) == np.sign((goal[0] - bx) * uy - (goal[1] - by) * ux)
    score = np.where(ok, room + 0.3 * np.minimum(lateral, 1.2) + 0.1 * side - 0.25 * np.where(ok, cost, 0.0),
                     -np.inf)
    r, c = np.unravel_index(int(np.argmax(score)), score.shape)
    return float(xs[r, c]), float(ys[r, c])
