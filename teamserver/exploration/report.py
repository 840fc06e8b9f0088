"""What to report to the refbox, and when.

Only the first value the refbox gets for a machine's property counts, so a
value, once sent, is frozen (the knowledge base remembers it) and resent
unchanged.  A property is reported

- as soon as the consistent machine set (:mod:`.symmetry`) knows it with
  confidence >= ``thresh``; or
- in the last ``margin`` seconds of exploration, whatever is known, as long
  as its expected points are positive: p * ok + (1 - p) * wrong > 0 with
  the profile's points (2016 zone +3/-2: p > 0.4; type +5/-4: p > 0.44;
  2025 zone and rotation +1/-1: p > 0.5).

2016 entries carry the type string announced for the light code.  When
robots read the tower through views (a detector, not the simulator's
oracle), ``lights`` (:class:`~.lights.LightGate`) decides instead of the
fused belief: the code its sure views give is reported at once, and none
while they give none, whatever the time left (a code read only
confidently is not worth its -4).  2017+ entries carry zone and rotation,
a rotation only with (or after) its zone.
"""
from __future__ import annotations

from collections.abc import Callable

from rll_bt.rules import Profile

from ..knowledge import model as M
from .lights import LightGate
from .symmetry import ConsistentSet


def expected_points(p: float, ok: int, wrong: int) -> float:
    return p * ok + (1.0 - p) * wrong


class Reporter:
    def __init__(self, profile: Profile, team_prefix: str, *, thresh: float = 0.9,
                 margin: float = 20.0, lights: LightGate | None = None):
        self.profile = profile
        self.lights = lights
        self.prefix = team_prefix
        self.thresh = thresh
        self.margin = margin

    def new_values(self, cs: ConsistentSet, reported: dict[str, dict], time_left: float,
                   type_string: Callable[[tuple[str, ...]], str | None]
                   ) -> dict[str, dict]:
        """Machine -> {property: value} to add to what was reported so far."""
        s = self.profile.scoring
        final = time_left <= self.margin
        out: dict[str, dict] = {}
        for name, g in sorted(cs.machines.items()):
            if not name.startswith(self.prefix + "-"):
                continue
            done = reported.get(name, {})
            new = {}

            def due(p: float, ok: int, wrong: int) -> bool:
                return p >= self.thresh or (final and expected_points(p, ok, wrong) > 0)

            if M.ZONE not in done and g.zone is not None and due(
                    g.zone_confidence, s.explore_zone_ok, s.explore_zone_wrong):
                new[M.ZONE] = g.zone
            zone_known = M.ZONE in done or M.ZONE in new
            if self.profile.exploration_reports == "type+zone":
                light, p = g.light, g.light_confidence
                if self.lights is not None and self.lights.views(name):
                    light = self.lights.code(name)
                    p = 1.0 if light is not None else 0.0
                if "type" not in done and light is not None and due(
                        p, s.explore_type_ok, s.explore_type_wrong):
                    t = type_string(light)
                    if t is not None:
                        new["type"] = t
            elif zone_known and "rotation" not in done and g.orientation is not None and due(
                    g.orientation_confidence, s.explore_rotation_ok, s.explore_rotation_wrong):
                new["rotation"] = int(g.orientation)
            if new:
                out[name] = new
        return out

    @staticmethod
    def entries(reported: dict[str, dict]) -> list[dict]:
        """MachineReport entries for everything reported so far."""
        return [{"name": name, **vals} for name, vals in sorted(reported.items()) if vals]
