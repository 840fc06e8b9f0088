"""Exploring a zone: drive to viewpoints around it, look, report.

:class:`ExploreZone` visits up to ``max_viewpoints`` free points on a ring
around the zone (nearest first, then the one farthest round the ring from
those visited, since a tag shows only on a station's input and output
faces), turns to face the zone and sweeps the camera across it, feeding
:class:`~.sightings.SightingCollector` at every poll (which publishes the
machine observations).  It stops early once a station in the zone is known
with ``min_confidence`` and, when ``want_light``, its light state has been
read; if the light is still missing it looks from in front of the
station's output face, then its input face.  When ``want_sure`` (by
default in profiles that score a station's rotation, 2017+), a station seen
in the zone must also be known with ``sure_confidence``: a station believed
in the zone (seen in this search, or placed there by the robot's machine
map, i.e. the team server's) is looked at from in front of its tag faces
(the nearer one first) before any ring viewpoint, since a far or oblique
view of a tag leaves its pose, and with it the rotation, weak.  A light read
but not settled (:meth:`~.sightings.SightingCollector.light_unsure`: its
views do not agree yet, :mod:`.light_views`) is read again before the robot
goes on: after a moment (``reread_wait`` seconds facing the station, when
the view is not even confident), then from a second view ``side_offset``
metres sideways of where the robot stands, facing the station (at most
``max_sideways`` of them per station).  When the tags' source reads towers
view by view (``light_views``: the camera's perception), a light missing
or unsure is read from where its tower shows whole
(:func:`~.light_views.light_viewpoints`: off the output face), a second
view from another such place, rather than from in front of a face at
1.2 m or sideways (where the station hides the lowest lamp).  The zone is explored when the activity succeeds:
``found`` lists the stations seen in it (possibly none).  It fails with
NAVIGATION_FAILED only when no viewpoint could be reached.
"""
from __future__ import annotations

import math

import numpy as np

from rll_bt.backend import Pose2D

from ..activity import Activity, Status
from ..errors import SkillError, SkillFailure
from ..navigation import Navigate, PoseGoal, approach_pose
from ..navigation.goals import feasible_distance
from ..navigation.motions import Turn
from .light_views import light_viewpoints
from .sightings import SightingCollector

#: share of the lowest lamp a light viewpoint should show (nearer ones showing less are taken last)
GOOD_LAMP_VIEW = 0.45
#: the least a light viewpoint may show (the camera's perception reads from 0.15)
MIN_LAMP_VIEW = 0.25


def ring_viewpoints(ctx, zone: int, radius: float | None = None, count: int = 8) -> list[Pose2D]:
    """Free poses on two rings around the zone centre (the outer one
    ``radius`` out, default half the zone's diagonal plus 0.5 m, and one at
    half that), facing the centre.  A point is free when the robot fits
    there in the map and no unmapped obstacle was seen within 0.5 m of it
    lately (``ctx.laser_memory``)."""
    rect = ctx.profile.zones.bounds(zone)
    cx, cy = rect.centre
    if radius is None:
        radius = 0.5 * math.hypot(rect.x_max - rect.x_min, rect.y_max - rect.y_min) + 0.5
    seen = ctx.laser_memory.points[ctx.laser_memory.expiry > ctx.clock.now()]
    out = []
    for r in (radius, 0.5 * radius):
        for k in range(count):
            a = 2.0 * math.pi * (k + (0.5 if r < radius else 0.0)) / count
            x, y = cx + r * math.cos(a), cy + r * math.sin(a)
            if not bool(ctx.costmap.is_free(x, y)):
                continue
            if len(seen) and np.hypot(seen[:, 0] - x, seen[:, 1] - y).min() < 0.5:
                continue
            out.append(Pose2D(x, y, math.atan2(cy - y, cx - x)))
    return out


def order_viewpoints(points: list[Pose2D], start: Pose2D, centre: tuple[float, float],
                     limit: int) -> list[Pose2D]:
    """Nearest first, then each next one farthest round the ring from those chosen."""
    if not points:
        return []
    left = list(points)
    first = min(left, key=lambda p: math.hypot(p.x - start.x, p.y - start.y))
    chosen = [first]
    left.remove(first)

    def bearing(p):
        return math.atan2(p.y - centre[1], p.x - centre[0])

    while left and len(chosen) < limit:
        def separation(p):
            return min(abs(math.remainder(bearing(p) - bearing(c), 2 * math.pi)) for c in chosen)
        nxt = max(left, key=separation)
        chosen.append(nxt)
        left.remove(nxt)
    return chosen


class ExploreZone(Activity):
    name = "explore zone"

    def __init__(self, ctx, zone: int, viewpoints: list[Pose2D] | None = None,
                 want_light: bool | None = None, max_viewpoints: int = 3, sweep: float = math.radians(100),
                 min_confidence: float = 0.5, collector: SightingCollector | None = None,
                 timeout: float | None = 240.0, want_sure: bool | None = None,
                 sure_confidence: float = 0.97, face_distance: float = 1.0, reread_wait: float = 1.5,
                 side_offset: float = 0.45, max_sideways: int = 2):
        super().__init__(ctx, timeout)
        self.zone = zone
        self.given = list(viewpoints) if viewpoints else None
        prof = ctx.profile
        self.want_light = (prof.exploration_reports == "type+zone") if want_light is None else want_light
        self.want_sure = (prof.exploration_reports != "type+zone") if want_sure is None else want_sure
        self.sure_confidence = sure_confidence
        self.face_distance = face_distance
        self.reread_wait, self.side_offset, self.max_sideways = reread_wait, side_offset, max_sideways
        self.max_viewpoints = max_viewpoints
        self.sweep = sweep
        self.min_confidence = min_confidence
        self.collector = collector or getattr(ctx, "sightings", None) or SightingCollector(ctx)
        # towers read view by view (the camera's perception): read them from where they show whole
        self.light_places = bool(getattr(getattr(ctx, "tags", None), "light_views", False))
        self.found: list[str] = []
        self.visited = 0
        self.child: Activity | None = None      # (set before _on_start: a start that fails still stops)
        self.name = f"explore {prof.zone_name(zone)}" if zone in prof.zones.all_zones else "explore"

    def _on_start(self) -> None:
        prof = self.ctx.profile
        if self.zone not in prof.zones.all_zones:
            raise SkillFailure(SkillError.INVALID_TASK, f"{self.zone} is not a zone of {prof.name}")
        self.ctx.update()
        centre = prof.zone_centre(self.zone)
        points = self.given or ring_viewpoints(self.ctx, self.zone)
        if not points:
            raise SkillFailure(SkillError.NAVIGATION_FAILED, f"no free viewpoint around {self.name[8:]}")
        self.plan = order_viewpoints(points, self.ctx.pose(), centre, self.max_viewpoints)
        self.light_sides = ["OUTPUT", "INPUT"]       # where to read a light not yet seen
        self.tag_sides: dict[str, list[str]] = {}     # station -> faces not yet looked at
        self.child: Activity | None = None
        self.phase = "next"
        self.visited = 0
        self.failures = 0
        self.lingered: set[tuple[str, int | None]] = set()   # (station, view) read again after a moment
        self.sideways: dict[str, int] = {}                    # station -> second views taken
        self.face_after_go: Pose2D | None = None              # look at this station after the drive
        self.rereads = 0

    # -- phases -----------------------------------------------------------
    def _done_enough(self) -> bool:
        found = self.collector.machines_in_zone(self.zone, self.min_confidence)
        if not found:
            return False
        if self.want_sure and any(self._unsure(m) for m in found):
            return False
        return not self.want_light or all(self.collector.light_state(m) is not None for m in found)

    def _unsure(self, machine: str) -> bool:
        est = self.collector.tracker.estimate(machine)
        return est is None or est.confidence < self.sure_confidence

    def _believed_in_zone(self) -> dict[str, Pose2D]:
        """Stations believed in the zone and their poses: on the robot's machine
        map, or (overriding the map) seen in the zone in this search."""
        prof = self.ctx.profile
        out = {}
        for m in self.ctx.machines.names():
            pose = self.ctx.machines.get(m)
            if pose is not None and prof.zone_at(pose.x, pose.y) == self.zone:
                out[m] = pose
        for m in self._seen_in_zone():
            out[m] = self.collector.tracker.estimate(m).pose
        return out

    def _face_goal(self) -> Activity | None:
        """Navigate in front of a tag face of a station believed in the zone
        whose pose is not sure yet (None when there is no such face left)."""
        mps = self.ctx.profile.mps
        for m, pose in sorted(self._believed_in_zone().items()):
            if not self._unsure(m):
                continue
            if m not in self.tag_sides:
                here = self.ctx.pose()
                self.tag_sides[m] = sorted(
                    ("INPUT", "OUTPUT"), key=lambda side: approach_pose(
                        pose, side, self.face_distance, mps=mps).distance_to(here))
            while self.tag_sides[m]:
                side = self.tag_sides[m].pop(0)
                d = feasible_distance(self.ctx, pose, side, self.face_distance, mps.belt_offset_y,
                                      minimum=0.6)
                if d is None:
                    continue
                self.phase = "go"
                return Navigate(self.ctx, PoseGoal(approach_pose(pose, side, d, mps=mps)),
                                position_tolerance=0.1, heading_tolerance=0.1, timeout=60.0, max_blocked=8.0)
        return None

    def _reread(self) -> Activity | None:
        """Read an unsure light again: after a moment, then from a second view
        sideways (see the module doc); None when there is nothing to read again."""
        if not self.want_light:
            return None
        views = self.collector.views
        for m in self._seen_in_zone():          # a tower glimpsed in a sweep: faced and read now
            if not self.collector.light_unsure(m):
                continue
            est = self.collector.tracker.estimate(m)
            view, verdict = views.current_view(m), views.verdict(m)
            if (m, view) not in self.lingered and (verdict is None or verdict.confidence < views.view_confidence):
                self.lingered.add((m, view))
                self.rereads += 1
                self.phase = "look"
                return _Linger(self.ctx, est.pose, self.reread_wait)
            if self.sideways.get(m, 0) < self.max_sideways:
                self.sideways[m] = self.sideways.get(m, 0) + 1
                goal = self._light_pose(est.pose, away=True) if self.light_places else None
                goal = goal or self._sideways_pose(est.pose)
                if goal is None:
                    continue
                self.rereads += 1
                self.phase = "go"
                self.face_after_go = est.pose
                return Navigate(self.ctx, PoseGoal(goal), position_tolerance=0.1, heading_tolerance=0.1,
                                timeout=30.0, max_blocked=5.0)
        return None

    def _free(self, x: float, y: float) -> bool:
        if not bool(self.ctx.costmap.is_free(x, y)):
            return False
        seen = self.ctx.laser_memory.points[self.ctx.laser_memory.expiry > self.ctx.clock.now()]
        return not (len(seen) and np.hypot(seen[:, 0] - x, seen[:, 1] - y).min() < 0.5)

    def _light_pose(self, station: Pose2D, away: bool = False) -> Pose2D | None:
        """A free place to read ``station``'s tower from (:func:`light_viewpoints`):
        the nearest that shows :data:`GOOD_LAMP_VIEW` of its lowest lamp, else the
        one that shows most; ``away``: at least 0.4 m from where the robot stands
        (another view)."""
        here = self.ctx.pose()
        best = None
        for seen, pose in light_viewpoints(station, self.ctx.profile):
            far = math.hypot(pose.x - here.x, pose.y - here.y)
            if seen < MIN_LAMP_VIEW or (away and far < 0.4) or not self._free(pose.x, pose.y):
                continue
            key = (seen < GOOD_LAMP_VIEW, far if seen >= GOOD_LAMP_VIEW else -seen)
            if best is None or key < best[0]:
                best = (key, pose)
        return None if best is None else best[1]

    def _sideways_pose(self, station: Pose2D) -> Pose2D | None:
        """A free pose ``side_offset`` m sideways of the robot (across its line of
        sight to ``station``), facing the station; the first side that is free."""
        here = self.ctx.pose()
        dx, dy = here.x - station.x, here.y - station.y
        r = math.hypot(dx, dy)
        if r < 1e-6:
            return None
        nx, ny = -dy / r, dx / r
        seen = self.ctx.laser_memory.points[self.ctx.laser_memory.expiry > self.ctx.clock.now()]
        for off in (self.side_offset, -self.side_offset, 0.8 * self.side_offset, -0.8 * self.side_offset):
            x, y = here.x + off * nx, here.y + off * ny
            if not bool(self.ctx.costmap.is_free(x, y)):
                continue
            if len(seen) and np.hypot(seen[:, 0] - x, seen[:, 1] - y).min() < 0.5:
                continue
            return Pose2D(x, y, math.atan2(station.y - y, station.x - x))
        return None

    def _next_child(self) -> Activity | None:
        again = self._reread()
        if again is not None:
            return again
        if self.want_sure:
            face = self._face_goal()
            if face is not None:
                return face
        if self.plan:
            vp = self.plan.pop(0)
            self.phase = "go"
            return Navigate(self.ctx, PoseGoal(vp), position_tolerance=0.1, heading_tolerance=0.1,
                            timeout=60.0, max_blocked=8.0)
        found = self.collector.machines_in_zone(self.zone, self.min_confidence)
        missing = [m for m in found if self.want_light and self.collector.light_state(m) is None]
        while missing and self.light_sides:
            side = self.light_sides.pop(0)
            est = self.collector.tracker.estimate(missing[0])
            if self.light_places:
                goal = self._light_pose(est.pose, away=side != "OUTPUT")
                if goal is None:
                    continue
                self.phase = "go"
                self.face_after_go = est.pose
                return Navigate(self.ctx, PoseGoal(goal), position_tolerance=0.1, heading_tolerance=0.1,
                                timeout=30.0, max_blocked=5.0)
            mps = self.ctx.profile.mps
            d = feasible_distance(self.ctx, est.pose, side, 1.2, mps.belt_offset_y, minimum=0.6)
            if d is None:
                continue
            self.phase = "go"
            return Navigate(self.ctx, PoseGoal(approach_pose(est.pose, side, d, mps=mps)),
                            position_tolerance=0.1, heading_tolerance=0.1, timeout=60.0, max_blocked=8.0)
        return None

    def _step(self, now: float) -> Status:
        self.collector.look()
        if self.child is None:
            if self.visited and self._done_enough():
                return self._succeed()
            self.child = self._next_child()
            if self.child is None:
                if self.visited == 0 and not self._seen_in_zone():
                    raise SkillFailure(SkillError.NAVIGATION_FAILED, f"no viewpoint of {self.name[8:]} reached")
                return self._succeed()
            self.child.start()
        status = self.child.poll()
        if status is Status.RUNNING:
            return Status.RUNNING
        if self.phase == "go":
            if status is Status.SUCCESS:
                self.visited += 1
                self.phase = "look"
                face, self.face_after_go = self.face_after_go, None
                self.child = (_Sweep(self.ctx, self.sweep) if face is None
                              else _Linger(self.ctx, face, self.reread_wait)).start()
                return Status.RUNNING
            if status is Status.FAILURE and self.child.error is SkillError.LOCALISATION_LOST:
                raise SkillFailure(self.child.error, self.child.message)
            self.failures += 1
            self.face_after_go = None
        self.child = None
        return Status.RUNNING

    def _seen_in_zone(self) -> list[str]:
        """Stations seen in the zone at all (a third of the confidence that
        ends the search early): weak evidence is still worth reporting."""
        return self.collector.machines_in_zone(self.zone, self.min_confidence / 3.0)

    def _succeed(self) -> Status:
        self.found = self._seen_in_zone()
        zone = self.ctx.profile.zone_name(self.zone)
        self.message = f"{zone}: {', '.join(self.found) if self.found else 'no station'} " \
                       f"({self.visited} viewpoints)"
        return Status.SUCCESS

    def _on_stop(self, status: Status) -> None:
        if self.child is not None and self.child.status is Status.RUNNING:
            self.child.cancel()
        self.ctx.stop_base()


class _Linger(Activity):
    """Turn to face ``target`` (a station's pose), then stand still ``wait``
    seconds: the camera reads its tower again, after a moment."""
    name = "read again"

    def __init__(self, ctx, target: Pose2D, wait: float):
        super().__init__(ctx, None)
        self.target = target
        self.wait = wait

    def _on_start(self) -> None:
        here = self.ctx.pose()
        self.turn = Turn(self.ctx, heading=math.atan2(self.target.y - here.y, self.target.x - here.x),
                         omega=0.6).start()
        self.still_since: float | None = None

    def _step(self, now: float) -> Status:
        if self.turn is not None:
            st = self.turn.poll()
            if st is Status.RUNNING:
                return Status.RUNNING
            self.turn = None              # turned (or could not): read from where it faces
            self.ctx.stop_base()
            self.still_since = now
        return Status.SUCCESS if now - self.still_since >= self.wait else Status.RUNNING

    def _on_stop(self, status: Status) -> None:
        if self.turn is not None and self.turn.status is Status.RUNNING:
            self.turn.cancel()


class _Sweep(Activity):
    """Turn -sweep/2, then +sweep: the camera passes over the zone."""
    name = "look around"

    def __init__(self, ctx, sweep: float):
        super().__init__(ctx, None)
        self.sweep = sweep

    def _on_start(self) -> None:
        self.turns = [Turn(self.ctx, by=-self.sweep / 2.0, omega=0.6),
                      Turn(self.ctx, by=self.sweep, omega=0.6)]
        self.turns[0].start()

    def _step(self, now: float) -> Status:
        st = self.turns[0].poll()
        if st is Status.RUNNING:
            return Status.RUNNING
        self.turns.pop(0)
        if not self.turns:
            return Status.SUCCESS
        self.turns[0].start()
        return Status.RUNNING
