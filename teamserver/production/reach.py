"""Places beside a station's belt that the field's walls leave no room in front of.

A robot puts a base on a ring station's slide and takes a cap carrier from a
cap station's shelf standing in front of the input face, beside the belt
(machine +y: the slide 0.25 m, the shelf slots 0.32, 0.24 and 0.16 m): docked, its
centre 0.27 m from the face, it moves sideways from the belt to the place (on its way in
it stops in front of the belt, 0.4 m out or closer where that leaves no room).  The real
generator stands a cyan RS or CS in the column by the x = 7 wall at rotation
270 (refbox-rules.md, field generation), which turns that side to the wall:
2025 seed 11 has C-RS1 in C_Z76, and every base put on its slide and every
discard there was blocked 1-4 cm short for the whole game (59 points): a robot
there stands 0.25 m from the wall, 2.5 cm more than its radius; 2025 seed 4 has
C-CS1's shelf slot 0 by the wall (0.18 m), slot 1 in reach (0.26 m: robots took
carriers from it).  :class:`Reach` says so
from the station's zone (or pose) and rotation as the team server knows them,
before a robot drives there: a place whose robot would stand closer than its
radius and ``margin`` to a wall.
"""
from __future__ import annotations

import math

from ..knowledge import model as M
from ..knowledge.kb import KnowledgeBase

#: m from the face to the robot's centre where it stands at the place: docked (the skills'
#: ``final_distance``), where it moves sideways from the belt to a slide or shelf slot; on its way
#: in it stops farther out (0.40 m) in front of the belt, or closer where that leaves no room.
#: (0.40 here, before: C-CS1 at 135 degrees by the x = -6 wall, 2016 seed 6, had every slot
#: walled by 4 mm for a pose 2 cm off and no grey cap all game, though slot 2 leaves 9 cm docked)
DOCKED_DISTANCE = 0.27


class Reach:
    """See the module doc.  ``margin``: metres beyond the robot's radius it needs to a
    wall: the motion guard's band beside the robot (``MotionGuard.lateral``, 0.02: a wall
    closer than that stops a move along it) and a centimetre the robot's line-up
    may stand off its slot."""

    def __init__(self, kb: KnowledgeBase, margin: float = 0.03, thresh: float = 0.9):
        self.kb = kb
        self.margin = margin
        self.thresh = thresh

    def _centre(self, machine: str) -> tuple[float, float] | None:
        """Where ``machine`` stands: from 2017 on the centre of its zone (the real
        generator puts every station there, refbox-rules.md; a pose fused from a few
        laser lines is centimetres off, and a centimetre decides here), the zone as
        reported, else as observed; in 2016 (stations anywhere in their zone) and
        while no zone is known, the fused pose."""
        prof = self.kb.profile
        if prof.year >= 2017:
            zone = self.kb.reported.get(machine, {}).get(M.ZONE)
            if zone is None:
                est = self.kb.estimate(machine, M.ZONE)
                zone = est.value if est is not None and est.confidence >= self.thresh else None
            if zone is not None:
                return prof.zone_centre(int(zone))
        return self.kb.machine_position(machine)

    def _placement(self, machine: str) -> tuple[tuple[float, float], float] | None:
        """((x, y), rotation in radians) of ``machine`` when both are known: the rotation
        reported to the refbox (2017+), else the observations' at ``thresh``."""
        rot = self.kb.reported.get(machine, {}).get("rotation")
        if rot is None:
            est = self.kb.estimate(machine, M.ORIENTATION)
            if est is None or est.confidence < self.thresh:
                return None
            rot = est.value
        pos = self._centre(machine)
        return (pos, math.radians(float(rot))) if pos is not None else None

    def walled(self, machine: str, lateral: float) -> bool:
        """Does a wall leave no room for a robot in front of ``machine``'s input at
        machine-frame y = ``lateral``?  False while its place is not known."""
        got = self._placement(machine)
        if got is None:
            return False
        (x, y), th = got
        prof = self.kb.profile
        ahead = prof.mps.depth / 2.0 + DOCKED_DISTANCE
        px = x + math.cos(th) * ahead - math.sin(th) * lateral
        py = y + math.sin(th) * ahead + math.cos(th) * lateral
        f = prof.field
        room = min(px - f.x_min, f.x_max - px, py - f.y_min, f.y_max - py)
        return room < prof.robot.radius + self.margin

    def slide_walled(self, rs: str) -> bool:
        return self.walled(rs, self.kb.profile.mps.slide_y)

    def shelf_walled(self, cs: str) -> set[int]:
        """The shelf slots of ``cs`` a wall leaves no room in front of."""
        return {i for i, lat in enumerate(self.kb.profile.mps.shelf_y) if self.walled(cs, lat)}

