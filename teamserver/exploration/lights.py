"""When a station's light code may go to the refbox: only on sure views.

A robot reading a signal tower with a detector tells which of its views of
the tower a reading comes from (a view: what it read standing at one
place; :mod:`skills.exploration.light_views`) and how sure the view is (the
mean probability its readings give the state), and the knowledge base keeps
each view's latest reading as one vote (:func:`~..knowledge.model.view_source`).
:class:`LightGate` lets a light code be reported only when ``min_sure``
(2) views read it with ``sure_confidence`` or more and no sure view read
another code (or the sure views that read it outnumber those by
``min_views``): a single sure view, wrong, cannot become a report.  Views below
that level neither report a code nor hold one back, and the code reported
is the one the sure views give (:meth:`LightGate.code`), whatever the
belief fused from all views says (``teamserver.exploration.report``).

What the rendered games say (``rll-bt sim --perception rendered``, seeds 1
and 2, five games, ``benchmarks/README.md``): the views that read a tower
wrong (the reader missing a lit lamp, from several places, several robots)
were 0.75-0.98 but one, at 0.993, while 81-87 % of the right views were
0.99 or more.  Agreement of confident views is no evidence here: two views
of one robot (seed 1) and views of two robots (seed 2) agreed on a wrong
code; but the wrong views came from where the station hid the tower's
lowest lamp, which the camera's perception no longer reads
(``skills.perception.light.region.tower_readable``).  Two sure views must
agree (``min_sure``), so that one wrong sure view is never reported alone.

In 2016 a station and its twin across the field show the same code
(:mod:`.symmetry`), so the views of both count.  Readings without a view
(handed over as exact: the simulator's oracle perception, which reads the
refbox's own state) are not gated: they pass as they did.
"""
from __future__ import annotations

from collections.abc import Hashable

from ..knowledge import model as M
from ..knowledge.kb import KnowledgeBase

#: the confidence at which a view may tell a code
SURE_CONFIDENCE = 0.99
#: sure views (of one robot from two places, of two robots, or of the station and its twin) that must agree
MIN_SURE = 2


class LightGate:
    def __init__(self, kb: KnowledgeBase, sure_confidence: float = SURE_CONFIDENCE, min_views: int = 2,
                 min_sure: int = MIN_SURE):
        self.kb = kb
        self.min_sure = min_sure
        self.sure_confidence = sure_confidence
        self.min_views = min_views

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
        sure = [v for _s, v, c in views if c >= self.sure_confidence]
        agree = sum(1 for v in sure if v == code)
        against = len(sure) - agree
        return agree >= self.min_sure and (against == 0 or agree - against >= self.min_views)

    def code(self, machine: str) -> tuple[str, ...] | None:
        """The code that passes (at most one can), or None."""
        for code in sorted({v for _s, v, c in self.views(machine) if c >= self.sure_confidence}):
            if self.passes(machine, code):
                return code
        return None

    def describe(self, machine: str) -> str:
        """What the views say, for logs."""
        views = self.views(machine)
        return ", ".join(f"{s}: {'+'.join(v) or 'none'} {c:.3f}" for s, v, c in views) or "no view"


def _with_twin(machine: str) -> tuple[str, ...]:
    team, _, kind = machine.partition("-")
    twin = {"C": "M", "M": "C"}.get(team)
    return (machine,) if twin is None else (machine, f"{twin}-{kind}")
