"""Exploration strategies: which zone an idle robot explores next.

- :class:`Algorithm1`: the paper's Algorithm 1, line by line, with the
  extensions its docstring lists (the default);
- :class:`Algorithm1Paper`: Algorithm 1 exactly as printed, for comparison;
- :class:`RandomStrategy`, :class:`NearestStrategy`: baselines;
- :class:`OracleStrategy`: knows where the machines stand (a lower bound
  for benchmarks only; a real game has no oracle).

Every strategy answers ``next_zone(view, pose) -> Decision | None``; the
``branch`` names the rule that chose (tests and logs read it).  Randomness
comes from a seeded :class:`random.Random`, so a game is reproducible.
"""
from __future__ import annotations

import random
from dataclasses import dataclass

from .view import ExplorationView, identification

DEFAULT_THRESH = 0.9


@dataclass(frozen=True)
class Decision:
    zone: int
    branch: str


#: Algorithm 1's branches that choose a zone without any observation in it
BLIND_BRANCHES = ("opposite", "random-start", "random-fallback")


class Strategy:
    name = "base"

    def __init__(self, seed: int = 0, thresh: float = DEFAULT_THRESH):
        self.rng = random.Random(seed)
        self.thresh = thresh

    def next_zone(self, view: ExplorationView, pose=None) -> Decision | None:
        raise NotImplementedError

    def redirect(self, view: ExplorationView, branch: str | None, pose=None) -> Decision | None:
        """A zone to send a robot to instead of the one it explores (chosen by
        ``branch``), or None to let it go on (the default)."""
        return None

    def _choose_random(self, zones: list[int]) -> int:
        return self.rng.choice(sorted(zones))

    def _first_look(self, view: ExplorationView, not_visited: list[int]) -> Decision | None:
        """Algorithm 1, lines 2-6 (no observation yet): the opposite zone,
        else a random unvisited one."""
        opposite = view.opposite_zone()
        if opposite is not None and opposite in not_visited:
            return Decision(opposite, "opposite")
        if not_visited:
            return Decision(self._choose_random(not_visited), "random-start")
        return None


def lowest_confidence(hyp: dict[int, float], zones) -> int:
    """getZoneWithLowestConfidence (ties: the lower zone number)."""
    return min(zones, key=lambda z: (hyp.get(z, 0.0), z))


class Algorithm1(Strategy):
    """Algorithm 1 of the paper.

    ::

        1  if observations = {} then
        2    if oppositeZone in notVisitedZones then return exploreZone(oppositeZone)
        5    else return exploreZone(chooseRandom(notVisitedZones))
        9  if numZonesNotVisited(observations) > 0 then
        11   return exploreZone(getZoneWithLowestConfidence(zonesNotVisited(observations)))
        14 if mFound(observations, thresh) < #MPS then
        15   return exploreZone(chooseRandom(notVisitedZones))
        18 else
        19   return exploreZone(getZoneWithLowestConfidence(...))

    ``observations`` are the zones where one of our machines is believed
    (:meth:`ExplorationView.hypotheses`) and not yet identified (confidence
    below ``thresh``): a machine known well enough from afar (2017+, where a
    far tag sighting gives zone and rotation) needs no visit.  Before line
    14 searches unvisited zones at random, a machine that is placed but not
    identified is looked at again when every machine is placed (an
    unvisited zone cannot hold anything new then; branch "weak-revisit").  At line 18 no observed zone is
    unvisited any more (line 9 returned otherwise), so, as the paper's text
    says ("if all zones are visited, the zone with the lowest confidence is
    chosen"), the lowest-confidence observed zone is revisited.  Zones another
    robot is already heading for count as being visited.  When line 15 finds
    no unvisited zone left, it too falls back to the lowest confidence.

    :meth:`redirect` lets the team server turn a robot away from a zone it
    chose blindly (no observation yet: "opposite", "random-start",
    "random-fallback") as soon as line 9 has an observed zone for it.

    These extensions (zones others head for, machines identified from afar,
    redirects) apply where a far sighting can identify a machine: from 2017
    on a tag seen from afar gives zone and rotation.  Under the 2016 rules
    the type is read from the light up close, so every observed zone needs
    a visit anyway; there line 9 takes every observed, unvisited zone as the
    paper does, and robots converge on observed zones instead of being sent
    blindly elsewhere by line 15 (measured over seeds 1..10 in 2016: all
    points after 33.4 s median with the paper's line 9, 41.8 s with the
    extensions; over 30 seeds in 2025: 40.3 s with them, 50.2 s without;
    ``benchmarks/README.md``).
    """

    name = "algorithm1"

    def next_zone(self, view: ExplorationView, pose=None) -> Decision | None:
        not_visited = view.not_visited()
        hyp = view.hypotheses()
        if not hyp:                                                     # line 1
            return self._first_look(view, not_visited)
        observed = self._observed_unvisited(view, hyp)
        if observed is not None:                                        # line 9
            return observed
        weak = [z for z, c in hyp.items() if c < self.thresh and z not in view.busy]
        if view.m_found(self.thresh) < view.n_mps and weak and view.all_observed():
            return Decision(lowest_confidence(hyp, weak), "weak-revisit")
        if view.m_found(self.thresh) < view.n_mps and not_visited:      # line 14
            return Decision(self._choose_random(not_visited), "random-fallback")
        zones = [z for z in hyp if z not in view.busy] or list(hyp)     # line 18
        return Decision(lowest_confidence(hyp, zones), "lowest-confidence")


    @staticmethod
    def _from_afar(view: ExplorationView) -> bool:
        """A far sighting identifies a machine (2017+: zone and rotation from its tag)."""
        return view.profile.exploration_reports != "type+zone"

    def _observed_unvisited(self, view: ExplorationView, hyp: dict[int, float]) -> Decision | None:
        if not self._from_afar(view):                 # 2016: the paper's line 9
            zones = [z for z in hyp if z not in view.visited]
        else:
            zones = [z for z, c in hyp.items()
                     if z not in view.visited and z not in view.busy and c < self.thresh]
        if not zones:
            return None
        return Decision(lowest_confidence(hyp, zones), "observed-unvisited")

    def redirect(self, view: ExplorationView, branch: str | None, pose=None) -> Decision | None:
        """A better zone for a robot exploring one it chose by ``branch``, or None."""
        if branch not in BLIND_BRANCHES or not self._from_afar(view):
            return None
        hyp = view.hypotheses()
        return self._observed_unvisited(view, hyp) if hyp else None


class Algorithm1Paper(Strategy):
    """Algorithm 1 exactly as printed in the paper, without the extensions of
    :class:`Algorithm1` (for comparison; ``--strategy algorithm1-paper``).

    ``observations`` are the zones where a machine of ours is believed
    (:meth:`ExplorationView.hypotheses`, any confidence); ``zonesNotVisited
    (observations)`` those of them no robot has explored yet;
    ``mFound(observations, thresh)`` the machines identified at ``thresh``.
    No zone is held back because another robot is heading for it, and
    nothing is known well enough from afar to skip a visit.  Two places
    where the pseudocode would act on an empty set are read as the paper's
    text says: at line 18 every observed zone has been visited (line 9
    returned otherwise), so the lowest-confidence *observed* zone is chosen
    ("if all zones are visited, the zone with the lowest confidence is
    chosen"); and when line 15 has no unvisited zone left, it does the same.
    """

    name = "algorithm1-paper"

    def next_zone(self, view: ExplorationView, pose=None) -> Decision | None:
        not_visited = view.not_visited()
        hyp = view.hypotheses()
        if not hyp:                                                     # line 1
            return self._first_look(view, not_visited)
        observed_not_visited = [z for z in hyp if z not in view.visited]
        if len(observed_not_visited) > 0:                               # lines 9-12
            return Decision(lowest_confidence(hyp, observed_not_visited), "observed-unvisited")
        if view.m_found(self.thresh) < view.n_mps and not_visited:      # lines 14-16
            return Decision(self._choose_random(not_visited), "random-fallback")
        return Decision(lowest_confidence(hyp, list(hyp)), "lowest-confidence")   # lines 18-20


class RandomStrategy(Strategy):
    """Unvisited zones in random order, then random weakly known ones."""

    name = "random"

    def next_zone(self, view: ExplorationView, pose=None) -> Decision | None:
        not_visited = view.not_visited()
        if not_visited:
            return Decision(self._choose_random(not_visited), "random")
        weak = [z for z, c in view.hypotheses().items() if c < self.thresh] or view.zones
        return Decision(self._choose_random(weak), "random-revisit") if weak else None


class NearestStrategy(Strategy):
    """The nearest unvisited zone, then the nearest weakly known one."""

    name = "nearest"

    def next_zone(self, view: ExplorationView, pose=None) -> Decision | None:
        not_visited = view.not_visited()
        if not_visited:
            return Decision(min(not_visited, key=lambda z: (view.distance(pose, z), z)),
                            "nearest")
        hyp = view.hypotheses()
        weak = [z for z, c in hyp.items() if c < self.thresh and z not in view.busy]
        if weak:
            return Decision(min(weak, key=lambda z: (view.distance(pose, z), z)),
                            "nearest-revisit")
        return Decision(lowest_confidence(hyp, hyp), "lowest-confidence") if hyp else None


class OracleStrategy(Strategy):
    """Knows each machine's zone (``truth``: machine name -> zone) and sends
    robots to the nearest zone of one of our machines not yet identified.
    For benchmarks only: it is the lower bound the others are measured by."""

    name = "oracle"

    def __init__(self, truth: dict[str, int], seed: int = 0, thresh: float = DEFAULT_THRESH):
        super().__init__(seed, thresh)
        self.truth = dict(truth)

    def next_zone(self, view: ExplorationView, pose=None) -> Decision | None:
        from rll_bt.rules import PREFIX
        own = [n for n in self.truth if n.startswith(PREFIX[view.team] + "-")]
        todo = []
        for name in own:
            g = view.guesses.get(name)
            if g is None or g.zone != self.truth[name] or identification(
                    view.profile, g) < self.thresh:
                todo.append(self.truth[name])
        free = [z for z in todo if z not in view.busy] or todo
        if not free:
            return None
        return Decision(min(free, key=lambda z: (view.distance(pose, z), z)), "oracle")


STRATEGIES = {"algorithm1": Algorithm1, "algorithm1-paper": Algorithm1Paper, "random": RandomStrategy,
              "nearest": NearestStrategy, "oracle": OracleStrategy}


def make_strategy(name: str, seed: int = 0, thresh: float = DEFAULT_THRESH,
                  truth: dict[str, int] | None = None) -> Strategy:
    """A strategy by name; ``oracle`` needs ``truth`` (machine -> zone)."""
    if name not in STRATEGIES:
        raise ValueError(f"unknown exploration strategy {name!r} "
                         f"(one of {', '.join(STRATEGIES)})")
    if name == "oracle":
        if truth is None:
            raise ValueError("the oracle strategy needs the true machine zones")
        return OracleStrategy(truth, seed, thresh)
    return STRATEGIES[name](seed, thresh)
