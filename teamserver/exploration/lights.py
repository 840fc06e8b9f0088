"""When a station's light code may go to the refbox: when views agree.

A robot reading a signal tower with a detector tells which of its views of
the tower a reading comes from (a view: what it read standing at one
place; :mod:`skills.exploration.light_views`), and the knowledge base keeps
each view's latest reading as one vote (:func:`~..knowledge.model.view_source`).
One view can be wrong in a way more frames of it do not cure (a glare, a
neighbour's glow, a tinted backdrop), so :class:`LightGate` lets a light
code be reported only when

- at least ``min_views`` views of at least ``min_robots`` robots read it
  with ``view_confidence`` or more, ahead of the views that read another
  code with that confidence by ``min_views`` (one confident view against it
  is outvoted only by three),
- or a view read it with ``sure_confidence`` or more and no confident view
  read another code (or the views that read it outnumber those by
  ``min_views``).

Views of one robot do not count as independent: in a rendered game
(``rll-bt sim --seed 1 --perception rendered``, measured in
``benchmarks/README.md``) one robot driving past a ring station read its
green lamp unlit from three places, at 0.95-0.98 each, and two of those
views let a wrong code out; every view that read that tower right was above
0.98, the wrong ones below 0.99.

In 2016 a station and its twin across the field show the same code
(:mod:`.symmetry`), so the views of both count.  Readings without a view
(handed over as exact: the simulator's oracle perception, which reads the
refbox's own state) are not gated: they pass as they did.
"""
from __future__ import annotations

from collections.abc import Hashable

from ..knowledge import model as M
from ..knowledge.kb import KnowledgeBase

#: the confidence at which a view's reading counts as a vote for its code
VIEW_CONFIDENCE = 0.9
#: the confidence at which one view alone may tell the code
SURE_CONFIDENCE = 0.99


class LightGate:
    def __init__(self, kb: KnowledgeBase, min_views: int = 2, view_confidence: float = VIEW_CONFIDENCE,
                 sure_confidence: float = SURE_CONFIDENCE, min_robots: int = 2):
        self.kb = kb
        self.min_robots = min_robots
        self.min_views = min_views
        self.view_confidence = view_confidence
        self.sure_confidence = sure_confidence

    def views(self, machine: str) -> list[tuple[str, Hashable, float]]:
        """(source, code, confidence) of every view of ``machine``'s tower and its twin's."""
        out = []
        for name in _with_twin(machine):
            mb = self.kb.machines.get(name)
            if mb is None:
                continue
            for source, value, conf, _t in mb.props[M.LIGHT].rows():
                if M.is_view_source(source):
                    out.append((f"{name}/{source}", tuple(sorted(value)), conf))
        return out

    def passes(self, machine: str, code: tuple[str, ...]) -> bool:
        """May ``code`` be reported as ``machine``'s light (see the module doc)?"""
        views = self.views(machine)
        if not views:
            return True                      # only readings handed over as exact
        code = tuple(sorted(code))
        confident = [(s, v, c) for s, v, c in views if c >= self.view_confidence]
        agree = [(s, c) for s, v, c in confident if v == code]
        against = len(confident) - len(agree)
        if any(c >= self.sure_confidence for _s, c in agree) and (
                against == 0 or len(agree) - against >= self.min_views):
            return True
        robots = {_robot_of(s) for s, _c in agree}
        return (len(agree) >= self.min_views and len(agree) - against >= self.min_views
                and len(robots) >= self.min_robots)

    def describe(self, machine: str) -> str:
        """What the views say, for logs."""
        views = self.views(machine)
        return ", ".join(f"{s}: {'+'.join(v) or 'none'} {c:.3f}" for s, v, c in views) or "no view"


def _robot_of(source: str) -> str:
    """"C-RS2/R3#v2" -> "R3"."""
    return source.split("/", 1)[1].split(M.VIEW_MARK, 1)[0]


def _with_twin(machine: str) -> tuple[str, ...]:
    team, _, kind = machine.partition("-")
    twin = {"C": "M", "M": "C"}.get(team)
    return (machine,) if twin is None else (machine, f"{twin}-{kind}")
