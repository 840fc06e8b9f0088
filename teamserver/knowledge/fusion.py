"""Fusing machine observations into beliefs, one property at a time.

A discrete property (zone, orientation, light, type) has K possible values.
An observation of value v with confidence c is read as a likelihood: the
robot says v with probability c when v is true and spreads 1 - c evenly over
the K - 1 other values.  From a uniform prior the posterior is then

    log P(v) = sum over robots r: log c_r            if r saw v
                                  log((1-c_r)/(K-1)) otherwise   (+ const)

Observations a robot repeats while it looks at a machine are *updates*
(the paper's agents resend when a confidence rises or a value is
corrected): within one visit, i.e. until the robot has been silent about
the property for ``revisit_gap`` seconds, it has one vote, its latest value
at the highest confidence it gave for it.  A later visit is new evidence and
votes again.  Agreement between robots or visits raises the confidence,
disagreement lowers it.  A confidence below 1/K is read as 1/K, i.e. as no
evidence: a glimpse (a robot's first sighting of a tag, before its tracker
trusts it) says v weakly, and taken literally the formula would count it as
evidence *against* v (c < (1 - c)/(K - 1)), so that one far-off glimpse could
outweigh a later close look at the same value.  Poses are fused as a
confidence-weighted mean (orientation as a circular mean) with a noisy-OR
confidence.
"""
from __future__ import annotations

import math
from collections.abc import Hashable, Iterable
from dataclasses import dataclass
from typing import Any

_C_MIN, _C_MAX = 1e-3, 0.999
#: seconds of silence after which a robot's next observation counts as a new visit
REVISIT_GAP = 10.0


@dataclass(frozen=True)
class Estimate:
    """Best value of a property, its probability, and who contributed."""

    value: Any
    confidence: float
    robots: tuple[str, ...]


class DiscreteBelief:
    """Belief over one discrete property of one machine (``k`` possible values)."""

    def __init__(self, k: int, revisit_gap: float = REVISIT_GAP):
        if k < 2:
            raise ValueError(f"a discrete property needs at least 2 values, not {k}")
        self.k = k
        self.revisit_gap = revisit_gap
        self._votes: list[list] = []          # [robot, value, confidence, last time]
        self._last: dict[str, list] = {}      # robot -> its current vote

    def add(self, robot: str, value: Hashable, confidence: float, t: float = 0.0) -> None:
        vote = self._last.get(robot)
        if vote is not None and t - vote[3] < self.revisit_gap:
            if vote[1] == value:
                vote[2] = max(vote[2], confidence)
            else:
                vote[1], vote[2] = value, confidence
            vote[3] = t
            return
        vote = [robot, value, confidence, t]
        self._votes.append(vote)
        self._last[robot] = vote

    def add_fixed(self, robot: str, value: Hashable, confidence: float, t: float = 0.0) -> None:
        """Set a source's statement outright (ground truth from the refbox)."""
        self._votes = [v for v in self._votes if v[0] != robot]
        vote = [robot, value, confidence, t]
        self._votes.append(vote)
        self._last[robot] = vote

    @property
    def empty(self) -> bool:
        return not self._votes

    def rows(self) -> list[tuple[str, Hashable, float, float]]:
        """(robot, value, confidence, time) of every vote, in order: added again
        in this order (:meth:`add`, the refbox's with :meth:`add_fixed`) they
        make the same belief (a robot's votes lie ``revisit_gap`` apart)."""
        return [(r, v, c, t) for r, v, c, t in self._votes]

    def sources(self, min_confidence: float = 0.0) -> set[str]:
        """Robots (sources) with a vote of at least ``min_confidence``."""
        return {v[0] for v in self._votes if v[2] >= min_confidence}

    def log_scores(self) -> tuple[dict[Hashable, float], float, int]:
        """(log score per observed value, log score of any unobserved value, #unobserved)."""
        seen: dict[Hashable, float] = {}
        base = 0.0
        floor = max(_C_MIN, 1.0 / self.k)
        for _robot, value, c, _t in self._votes:
            c = min(max(c, floor), _C_MAX)
            miss = math.log((1.0 - c) / (self.k - 1))
            base += miss
            seen[value] = seen.get(value, 0.0) + math.log(c) - miss
        scores = {v: base + s for v, s in seen.items()}
        return scores, base, max(self.k - len(scores), 0)

    def distribution(self) -> tuple[dict[Hashable, float], float]:
        """(P(value) for each observed value, P(each single unobserved value))."""
        scores, other, n_other = self.log_scores()
        if not scores:
            return {}, 1.0 / self.k
        top = max(max(scores.values()), other)
        weights = {v: math.exp(s - top) for v, s in scores.items()}
        w_other = math.exp(other - top)
        total = sum(weights.values()) + n_other * w_other
        return {v: w / total for v, w in weights.items()}, w_other / total

    def probability(self, value: Hashable) -> float:
        dist, other = self.distribution()
        return dist.get(value, other)

    def estimate(self) -> Estimate | None:
        dist, _ = self.distribution()
        if not dist:
            return None
        value = max(dist, key=lambda v: (dist[v], _order_key(v)))
        robots = tuple(sorted({r for r, v, _c, _t in self._votes if v == value}))
        return Estimate(value, dist[value], robots)


class PoseBelief:
    """Confidence-weighted mean of each robot's latest pose (x, y, ori)."""

    def __init__(self) -> None:
        self._by_robot: dict[str, tuple[tuple[float, float, float], float]] = {}
        self._times: dict[str, float] = {}

    def add(self, robot: str, value: Iterable[float], confidence: float, t: float = 0.0) -> None:
        x, y, ori = (float(v) for v in value)
        self._by_robot[robot] = ((x, y, ori), confidence)
        self._times[robot] = t

    add_fixed = add

    @property
    def empty(self) -> bool:
        return not self._by_robot

    def rows(self) -> list[tuple[str, tuple[float, float, float], float, float]]:
        """(robot, pose, confidence, time) of each robot's latest pose: added again, the same belief."""
        return [(r, v, c, self._times[r]) for r, (v, c) in self._by_robot.items()]

    def estimate(self) -> Estimate | None:
        if not self._by_robot:
            return None
        w_sum = sx = sy = sc = ss = 0.0
        miss = 1.0
        for (x, y, ori), c in self._by_robot.values():
            w = max(c, _C_MIN)
            w_sum += w
            sx, sy = sx + w * x, sy + w * y
            sc, ss = sc + w * math.cos(ori), ss + w * math.sin(ori)
            miss *= 1.0 - min(c, _C_MAX)
        value = (sx / w_sum, sy / w_sum, math.atan2(ss, sc))
        return Estimate(value, 1.0 - miss, tuple(sorted(self._by_robot)))


def _order_key(v: Any) -> str:
    """Deterministic tie-break between equally likely values."""
    return repr(v)
