"""Station places the robots keep failing at, taken out of planning for a while.

A robot that fails again and again at the same place (a ring station's
slide it cannot reach, a cap station output it cannot grab from) costs the
team the whole game if the plan keeps sending it there: every product that
needs the place is retried and repaired until the game ends, holding a
product slot and robots.  :class:`StationHealth` counts failures in a row
per *place* (a station, or a ring station's slide) and, after
``max_failures`` of them, reports the place as unusable for ``pause``
seconds (twice as long each time it comes to that again); a success there
clears the count.  The planner then plans around
the place (another station with the same ring colour or cap, or other
orders), and products that need it are repaired or abandoned.

Only ring and cap stations are taken out: the base and delivery stations
have no alternative, so giving up on them would stop production.
Places are ``"C-RS2"`` (the station: its input or output) and
``"C-RS2:SLIDE"`` (a ring station's slide only: the bases put there and the
workpieces discarded there, :mod:`.slides`).  Times are seconds of the
server's clock; the state lives in the knowledge base (``health``).
"""
from __future__ import annotations

import logging

from ..knowledge import model as M
from ..knowledge.kb import KnowledgeBase

log = logging.getLogger("teamserver.production.health")

#: errors that say nothing about the place (the task was stopped, or the game was)
NEUTRAL_ERRORS = ("CANCELLED", "NOT_RUNNING", "MACHINE_BROKEN", "INVALID_TASK")


def place_of(task: M.Task) -> str | None:
    """The place a production task works at (None: no station, or BS/DS)."""
    machine = task.machine
    if not machine or machine[2:4] not in ("RS", "CS"):
        return None
    if task.kind in (M.PUT_WORKPIECE, M.DISCARD) and task.params.get("side") == M.SLIDE:
        return f"{machine}:{M.SLIDE}"
    return machine


class StationHealth:
    """Failure counts per place and the places paused now (see the module doc)."""

    def __init__(self, kb: KnowledgeBase, *, max_failures: int = 4, pause: float = 150.0):
        self.kb = kb
        self.max_failures = max_failures
        self.pause = pause

    def _state(self) -> dict:
        return dict(self.kb.get("health") or {"fails": {}, "until": {}})

    def outcome(self, task: M.Task, ok: bool, error: str, now: float) -> bool:
        """Book a finished task; True when its place became unusable just now."""
        place = place_of(task)
        if place is None or (not ok and error in NEUTRAL_ERRORS):
            return False
        st = self._state()
        fails, until = dict(st["fails"]), dict(st["until"])
        if ok:
            if fails.pop(place, None) is not None:
                self.kb.set("health", {**st, "fails": fails})
            return False
        n = fails.get(place, 0) + 1
        fails[place] = n
        marks = dict(st.get("marks", {}))
        paused = False
        if n >= self.max_failures:
            marks[place] = marks.get(place, 0) + 1
            pause = self.pause * 2 ** (marks[place] - 1)
            until[place] = now + pause
            fails[place] = 0
            paused = True
            log.warning("%s failed %d times in a row: not planned with for %.0f s",
                        place, n, pause)
        self.kb.set("health", {"fails": fails, "until": until, "marks": marks})
        return paused

    def unusable(self, now: float) -> frozenset[str]:
        """Places paused at server time ``now``."""
        return frozenset(p for p, t in self._state()["until"].items() if t > now)

    def usable(self, task: M.Task, now: float) -> bool:
        place = place_of(task)
        return place is None or place not in self.unusable(now)
