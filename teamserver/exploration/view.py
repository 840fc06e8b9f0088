"""What an exploration strategy sees: zones, visits and machine hypotheses.

Built from the knowledge base for one decision.  A *hypothesis* is a zone
where the consistent machine set (:mod:`.symmetry`) puts one of our machines,
or where a robot reported one of ours; its confidence is how well that
machine is identified: the lowest confidence of the properties a report
needs (zone and light code in 2016, zone and orientation from 2017 on).
A light code the light gate does not let out yet (read through views, not
two sure views that agree: :class:`~.lights.LightGate`) is not known,
however confident the belief fused from all views is: its zone stays weak,
and the strategy sends a robot to read it again.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

from rll_bt.rules import PREFIX, Profile, mirror_machine_name

from ..knowledge import model as M
from .symmetry import ConsistentSet, MachineGuess, consistent_set


def report_properties(profile: Profile) -> tuple[str, ...]:
    """Machine properties a report scores: (zone, light) or (zone, orientation)."""
    return (M.ZONE, M.LIGHT) if profile.exploration_reports == "type+zone" else (M.ZONE,
                                                                               M.ORIENTATION)


def identification(profile: Profile, guess: MachineGuess) -> float:
    """How well ``guess`` is known: the lowest confidence of the reported properties."""
    confs = {M.ZONE: guess.zone_confidence if guess.zone is not None else 0.0,
             M.LIGHT: guess.light_confidence if guess.light is not None else 0.0,
             M.ORIENTATION: (guess.orientation_confidence
                             if guess.orientation is not None else 0.0)}
    return min(confs[p] for p in report_properties(profile))


def sure_properties(profile: Profile, guess: MachineGuess, thresh: float) -> dict:
    """The reported properties of ``guess`` known at confidence ``thresh`` or
    better: {"zone": int, "light": sorted colours, "orientation": degrees}."""
    have = {M.ZONE: (guess.zone, guess.zone_confidence),
            M.LIGHT: (tuple(sorted(guess.light)) if guess.light is not None else None, guess.light_confidence),
            M.ORIENTATION: (guess.orientation, guess.orientation_confidence)}
    out = {}
    for p in report_properties(profile):
        value, conf = have[p]
        if value is not None and conf >= thresh:
            out[p] = int(value) if p != M.LIGHT else value
    return out


def opposite_zone(profile: Profile, team: str, zones: list[int]) -> int | None:
    """The paper's first target: the top-most left zone when the team starts
    at the right start box, the top-most right zone when it starts at the
    left, among the zones the team explores."""
    if not zones:
        return None
    start_x = profile.insertion[team].centre[0] if team in profile.insertion else 0.0
    sign = 1.0 if start_x > 0 else -1.0

    def key(z: int) -> tuple[float, float]:
        x, y = profile.zone_centre(z)
        return (-y, sign * x)

    return min(zones, key=key)


@dataclass
class ExplorationView:
    profile: Profile
    team: str
    zones: list[int]                            # zones this team explores
    visited: set[int] = field(default_factory=set)
    busy: set[int] = field(default_factory=set)  # targets of other robots' open tasks
    guesses: dict[str, MachineGuess] = field(default_factory=dict)   # own machines
    raw_zones: dict[str, int] = field(default_factory=dict)  # own machine -> best single zone
    consistent: ConsistentSet | None = None
    observed: set[str] = field(default_factory=set)   # machines some robot reported

    @classmethod
    def from_kb(cls, kb, team: str, zones: list[int], busy: set[int] = frozenset(),
                cs: ConsistentSet | None = None, lights=None) -> ExplorationView:
        """The view of ``kb``; ``cs``: its consistent set when already made;
        ``lights``: the light gate (see the module doc)."""
        cs = consistent_set(kb.profile, kb.machines) if cs is None else cs
        prefix = PREFIX[team] + "-"
        raw = {}
        for name, mb in kb.machines.items():
            est = mb.estimate(M.ZONE)
            if name.startswith(prefix) and est is not None:
                raw[name] = int(est.value)
        observed = set(kb.observed_machines())
        own = cs.own(team)
        if lights is not None:
            own = {n: replace(g, light_confidence=0.0) if lights.views(n) and lights.code(n) is None else g
                   for n, g in own.items()}
        return cls(kb.profile, team, list(zones), set(kb.visited), set(busy),
                   own, raw, cs, observed)

    @property
    def n_mps(self) -> int:
        return len(self.profile.machine_types)

    def hypotheses(self) -> dict[int, float]:
        """Zone -> identification confidence of the machine believed there.

        Only machines a robot reported (or whose twin it reported) count: a
        zone the rules fix (2016 BS and DS) is no observation by itself."""
        hyp: dict[int, float] = {}
        for name, g in self.guesses.items():
            if name not in self.observed and mirror_machine_name(name) not in self.observed:
                continue
            if g.zone is not None:
                hyp[g.zone] = max(hyp.get(g.zone, 0.0), identification(self.profile, g))
        for z in self.raw_zones.values():
            hyp.setdefault(z, 0.0)
        return hyp

    def all_observed(self) -> bool:
        """Is every one of our machines placed by an observation (of itself or
        of its twin)?  Then a search of unvisited zones can find nothing new."""
        return len(self.guesses) == self.n_mps and all(
            g.zone is not None and (name in self.observed or mirror_machine_name(name) in self.observed)
            for name, g in self.guesses.items())

    def m_found(self, thresh: float) -> int:
        """mFound: our machines identified with confidence >= ``thresh``."""
        return sum(1 for g in self.guesses.values()
                   if g.zone is not None and identification(self.profile, g) >= thresh)

    def not_visited(self) -> list[int]:
        """notVisitedZones, without zones another robot is on its way to (unless
        that would leave none)."""
        left = [z for z in self.zones if z not in self.visited]
        free = [z for z in left if z not in self.busy]
        return free or left

    def opposite_zone(self) -> int | None:
        return opposite_zone(self.profile, self.team, self.zones)

    def distance(self, pose, zone: int) -> float:
        if pose is None:
            return 0.0
        x, y = self.profile.zone_centre(zone)
        return math.hypot(x - pose[0], y - pose[1])
