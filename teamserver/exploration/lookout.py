"""Going for the rotations still lacking once every zone is reported (2017+).

From 2017 on exploration runs inside PRODUCTION: the team server stops
exploring as soon as every own station's zone is reported, and production
begins.  A rotation that was not sure enough by then would never be
reported, and the refbox refuses PrepareMachine for that station until the
exploration window is over (the rotation is part of a correct report).
:class:`Lookout` picks, while the window lasts, the stations whose zone is
reported but whose rotation is not, and sends one robot at a time to look
at such a station's tag faces: an ``explore_zone`` task on the station's
zone with viewpoints in front of its input and output faces, where a tag
is seen head-on and close (a far, oblique look is what left the rotation
weak).  The team server keeps reporting during the window, so the look's
observations are reported as soon as they are sure.

Positions are field-frame metres; a machine pose is (x, y, ori) with ``ori``
in radians, the machine x axis running from the output face to the input
face (:mod:`rll_bt.rules.geometry`).  Times are seconds.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

from rll_bt.rules import MPS, Profile

from ..knowledge import model as M
from .symmetry import ConsistentSet, consistent_set

#: task parameter that marks an ``explore_zone`` task as a look at one machine
LOOK = "look"


@dataclass(frozen=True)
class LookTarget:
    """A station to look at: its zone and the poses (x, y, theta) to look from."""

    machine: str
    zone: int
    viewpoints: tuple[tuple[float, float, float], ...]
    confidence: float              # how sure its rotation is now


def is_look(task: M.Task) -> bool:
    """Is ``task`` a look at one machine (see :class:`Lookout`)?"""
    return task.kind == M.EXPLORE_ZONE and bool(task.params.get(LOOK))


def face_viewpoints(profile: Profile, pose, distance: float = 0.9, *,
                    others=(), clearance: float = 0.75, wall_margin: float = 0.35
                    ) -> list[tuple[float, float, float]]:
    """Poses facing the input face, then the output face of a machine at
    ``pose``, the robot centre ``distance`` m in front of the face on the
    machine's x axis.  A pose outside the field (by ``wall_margin``) or
    closer than ``clearance`` to the centre of another machine in
    ``others`` ((x, y) positions) is left out."""
    x, y, ori = (float(v) for v in pose[:3])
    field = profile.field
    out = []
    for sign in (1.0, -1.0):                     # input face (+x), then output face
        d = MPS.depth / 2.0 + distance
        vx, vy = x + sign * d * math.cos(ori), y + sign * d * math.sin(ori)
        if not (field.x_min + wall_margin <= vx <= field.x_max - wall_margin
                and field.y_min + wall_margin <= vy <= field.y_max - wall_margin):
            continue
        if any(math.hypot(vx - ox, vy - oy) < clearance for ox, oy in others):
            continue
        out.append((vx, vy, math.atan2(y - vy, x - vx)))
    return out


class Lookout:
    """Which station to look at next for its rotation, and how.

    ``thresh``: the reporting confidence (a rotation at least this sure is
    reported without a look); ``min_time_left``: no new look with fewer
    seconds of exploration left (the last-seconds report takes over);
    ``max_looks``: looks per machine before it is left to that report;
    ``max_robots``: looks at the same time (the other robots produce).
    """

    def __init__(self, profile: Profile, prefix: str, *, thresh: float = 0.9,
                 min_time_left: float = 20.0, max_looks: int = 3, max_robots: int = 1):
        self.profile = profile
        self.prefix = prefix
        self.thresh = thresh
        self.min_time_left = min_time_left
        self.max_looks = max_looks
        self.max_robots = max_robots
        self._cs: tuple[int, ConsistentSet] | None = None

    def consistent(self, kb) -> ConsistentSet:
        """The consistent machine set of ``kb``, recomputed only when an
        observation came in since the last call."""
        if self._cs is None or self._cs[0] != kb.observation_count:
            self._cs = (kb.observation_count, consistent_set(self.profile, kb.machines))
        return self._cs[1]

    def active(self) -> bool:
        """Does this profile score rotations (2017+)?"""
        return self.profile.exploration_reports != "type+zone"

    def lacking(self, cs: ConsistentSet, reported: dict[str, dict]) -> list[str]:
        """Own machines whose zone is reported and whose rotation is not, and
        not yet sure enough to be reported, least sure first."""
        out = []
        for name, g in cs.machines.items():
            if not name.startswith(self.prefix + "-"):
                continue
            done = reported.get(name, {})
            if M.ZONE not in done or "rotation" in done:
                continue
            conf = g.orientation_confidence if g.orientation is not None else 0.0
            if conf < self.thresh:
                out.append((conf, name))
        return [n for _c, n in sorted(out)]

    def done_looks(self, kb, cs: ConsistentSet) -> list[M.Task]:
        """Looks under way whose machine no longer lacks its rotation (it was
        reported, or is sure enough to be at the next report)."""
        lacking = set(self.lacking(cs, kb.reported))
        return [t for t in kb.open_tasks() if is_look(t) and t.params[LOOK] not in lacking]

    def targets(self, kb, cs: ConsistentSet, time_left: float) -> list[LookTarget]:
        """Stations to look at now (at most ``max_robots`` minus the looks
        under way), least sure rotation first."""
        if not self.active() or time_left < self.min_time_left:
            return []
        open_looks = [t for t in kb.open_tasks() if is_look(t) and t.state == M.ASSIGNED]
        room = self.max_robots - len(open_looks)
        if room <= 0:
            return []
        busy = {t.params[LOOK] for t in open_looks}
        tried: dict[str, int] = {}
        for t in kb.tasks.values():
            if is_look(t) and t.state != M.PENDING:
                tried[t.params[LOOK]] = tried.get(t.params[LOOK], 0) + 1
        out = []
        for name in self.lacking(cs, kb.reported):
            if name in busy or tried.get(name, 0) >= self.max_looks:
                continue
            g = cs.machines[name]
            out.append(LookTarget(name, int(kb.reported[name][M.ZONE]),
                                  tuple(self._viewpoints(kb, name, tried.get(name, 0))),
                                  g.orientation_confidence if g.orientation is not None else 0.0))
            if len(out) >= room:
                break
        return out

    def _viewpoints(self, kb, name: str, tries: int) -> list[tuple[float, float, float]]:
        """In front of the faces of the fused pose; none (the robot's own
        ring around the zone) when the pose is unknown, no face is clear, or
        an earlier look from the faces did not make the rotation sure."""
        pose = kb.estimate(name, M.POSE)
        if pose is None or tries >= 2:
            return []
        others = []
        for other in self.profile.machines():
            if other == name:
                continue
            pos = kb.machine_position(other)
            if pos is not None:
                others.append(pos)
        return face_viewpoints(self.profile, pose.value, others=others)

    @staticmethod
    def pick_robot(robots, target: LookTarget, kb) -> M.Robot | None:
        """The robot to send: the nearest one that has not already told the
        team server about this machine with some confidence (a robot repeats
        a sighting only when it is surer than before, so a second look by
        the same robot may add nothing), else the nearest."""
        if not robots:
            return None
        mb = kb.machines.get(target.machine)
        voted = set() if mb is None else mb.props[M.ORIENTATION].sources(0.5)
        goal = target.viewpoints[0][:2] if target.viewpoints else kb.profile.zone_centre(target.zone)

        def key(r):
            d = math.hypot(r.pose[0] - goal[0], r.pose[1] - goal[1]) if r.pose else 0.0
            return (f"R{r.number}" in voted, d, r.number)
        return min(robots, key=key)
