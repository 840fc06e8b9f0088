"""Where an idle robot should wait: away from the stations' approach points.

An idle robot stays where its last task ended, which is in front of a
station; the next robot sent to that station then cannot get there.  These
functions find the robots in the way and a free spot to park each of them;
:class:`Parking` sends idle robots in the way there (GO_TO tasks).  A
parking robot counts as idle: real work cancels its GO_TO.  A failed GO_TO
waits ``park_retry`` seconds.

All positions are field-frame metres; a machine pose is (x, y, ori) with
``ori`` in radians (the machine frame's x axis runs from the output face to
the input face, see :mod:`rll_bt.rules.geometry`).
"""
from __future__ import annotations

import logging
import math
from dataclasses import dataclass

import numpy as np

from rll_bt.rules import MPS, Profile

from ..knowledge import model as M
from ..knowledge.kb import KnowledgeBase
from .config import DispatchConfig
from .fleet import Fleet

log = logging.getLogger("teamserver.dispatch")

#: robot centre to the station face when docked (the skills' default approach distance), m
APPROACH_DISTANCE = 0.62
#: half the diagonal of a station's footprint: its centre to its corners, m
STATION_RADIUS = math.hypot(MPS.depth, MPS.width) / 2.0


@dataclass(frozen=True)
class ParkingConfig:
    """Metres that steer parking."""

    near: float = 1.2          # a robot closer than this to an approach point is in the way
    want: float = 1.0          # clearance a parking spot should have; nearest such spot wins
    grid: float = 0.5          # spacing of the candidate spots
    wall_margin: float = 0.5   # candidate spots keep this far from the field edge
    same_spot: float = 0.5     # never park at a spot this close to where the robot stands


def station_points(kb: KnowledgeBase, profile: Profile) -> tuple[list, list]:
    """(approach points, station centres) of every machine of both teams whose
    position is known.  A station known only by its position (no pose) gives
    its centre as an approach point too."""
    approach, centres = [], []
    for name in profile.machines():
        pose = kb.estimate(name, M.POSE)
        if pose is not None:
            x, y, ori = (float(v) for v in pose.value[:3])
            d = MPS.depth / 2.0 + APPROACH_DISTANCE
            approach += [(x + d * math.cos(ori), y + d * math.sin(ori)),
                         (x - d * math.cos(ori), y - d * math.sin(ori))]
            centres.append((x, y))
            continue
        pos = kb.machine_position(name)
        if pos is not None:
            approach.append(pos)
            centres.append(pos)
    return approach, centres


def in_the_way(pose, approach: list, config: ParkingConfig = ParkingConfig()) -> bool:
    """Whether a robot at ``pose`` (x, y, ...) stands within ``config.near`` of
    an approach point."""
    if pose is None or not approach:
        return False
    a = np.asarray(approach, dtype=float)
    return bool(np.min(np.hypot(a[:, 0] - pose[0], a[:, 1] - pose[1])) < config.near)


def clearance(points: np.ndarray, profile: Profile, approach: list, centres: list,
              others: list) -> np.ndarray:
    """Free distance (m) around each of ``points`` (N x 2): to the field edge,
    station footprints, approach points, other robots and their parking spots,
    and the insertion areas."""
    f = profile.field
    x, y = points[:, 0], points[:, 1]
    out = np.minimum.reduce([x - f.x_min, f.x_max - x, y - f.y_min, f.y_max - y])
    for (cx, cy) in centres:
        out = np.minimum(out, np.hypot(x - cx, y - cy) - STATION_RADIUS)
    for (px, py) in list(approach) + list(others):
        out = np.minimum(out, np.hypot(x - px, y - py))
    for r in profile.insertion.values():
        dx = np.maximum.reduce([r.x_min - x, np.zeros_like(x), x - r.x_max])
        dy = np.maximum.reduce([r.y_min - y, np.zeros_like(y), y - r.y_max])
        out = np.minimum(out, np.hypot(dx, dy))
    return out


def candidates(profile: Profile, config: ParkingConfig = ParkingConfig()) -> np.ndarray:
    """Candidate parking spots: a grid over the field, ``wall_margin`` from its edge."""
    f = profile.field
    xs = np.arange(f.x_min + config.wall_margin, f.x_max - config.wall_margin + 1e-9, config.grid)
    ys = np.arange(f.y_min + config.wall_margin, f.y_max - config.wall_margin + 1e-9, config.grid)
    gx, gy = np.meshgrid(xs, ys)
    return np.column_stack([gx.ravel(), gy.ravel()])


def parking_spot(pose, profile: Profile, approach: list, centres: list, others: list,
                 config: ParkingConfig = ParkingConfig()) -> tuple[float, float] | None:
    """The spot to park a robot standing at ``pose``: the nearest candidate with
    at least ``config.want`` clearance, else the one with the most; never one
    within ``config.same_spot`` of the robot; None when no spot is freer than
    where the robot already stands."""
    pts = candidates(profile, config)
    if pose is not None:
        away = np.hypot(pts[:, 0] - pose[0], pts[:, 1] - pose[1]) >= config.same_spot
        pts = pts[away]
    if len(pts) == 0:
        return None
    free = clearance(pts, profile, approach, centres, others)
    here = None if pose is None else float(
        clearance(np.array([[pose[0], pose[1]]]), profile, approach, centres, others)[0])
    good = np.nonzero(free >= config.want)[0]
    if len(good) and pose is not None:
        d = np.hypot(pts[good, 0] - pose[0], pts[good, 1] - pose[1])
        best = int(good[int(np.argmin(d))])
    else:
        best = int(np.argmax(free))
    if here is not None and free[best] <= here:
        return None
    return float(pts[best, 0]), float(pts[best, 1])


class Parking:
    """Sends idle robots that stand in front of a station to a free spot (see the
    module doc)."""

    def __init__(self, kb: KnowledgeBase, clock, fleet: Fleet, config: DispatchConfig,
                 parking: ParkingConfig | None = None):
        self.kb = kb
        self.clock = clock
        self.fleet = fleet
        self.config = config
        self.parking = parking if parking is not None else ParkingConfig()
        self._wait: dict[int, float] = {}       # robot -> server time it may park again

    def failed(self, robot: M.Robot) -> None:
        """``robot``'s GO_TO failed: it does not park again for ``park_retry`` s."""
        self._wait[robot.number] = self.clock.now() + self.config.park_retry

    def park(self) -> list[M.Task]:
        """Send idle robots that stand in front of a station to a free spot
        (GO_TO tasks); returns the tasks assigned now."""
        if not self.config.park:
            return []
        now = self.clock.now()
        profile = self.kb.profile
        approach, centres = station_points(self.kb, profile)
        if not approach:
            return []
        out = []
        for r in self.fleet.idle_robots():
            if r.pose is None or self._wait.get(r.number, -math.inf) > now:
                continue
            if not in_the_way(r.pose, approach, self.parking):
                continue
            spot = parking_spot(r.pose, profile, approach, centres,
                                self._other_robots(r), self.parking)
            if spot is None:
                self._wait[r.number] = now + self.config.park_retry
                continue
            theta = math.atan2(spot[1] - r.pose[1], spot[0] - r.pose[0])
            t = M.Task(self.kb.next_id("task"), M.GO_TO,
                       {"x": spot[0], "y": spot[1], "theta": theta}, created=now)
            self.fleet.assign(t, r)
            log.info("robot %d parks at (%.2f, %.2f), out of the stations' way", r.number, *spot)
            out.append(t)
        return out

    def _other_robots(self, robot: M.Robot) -> list[tuple[float, float]]:
        """Where the other robots stand and where they park."""
        pts = [(o.pose[0], o.pose[1]) for o in self.kb.active_robots()
               if o.number != robot.number and o.pose is not None]
        pts += [(float(t.params["x"]), float(t.params["y"])) for t in self.kb.open_tasks()
                if t.kind == M.GO_TO and t.robot != robot.number]
        return pts
