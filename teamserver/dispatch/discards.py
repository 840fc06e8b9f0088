"""Robots holding a workpiece nothing needs: discard it, and wait after a failure.

A failed discard (without a station) is not resent at once: the robot
waits ``discard_backoff`` seconds (doubling per failure in a row, at most
4x) and may be parked meanwhile, so the next try happens somewhere else.
"""
from __future__ import annotations

import math

from ..knowledge import model as M
from ..knowledge.kb import KnowledgeBase
from ..production.cleanup import Cleanup
from .config import DispatchConfig
from .fleet import Fleet


class Discards:
    """See the module doc."""

    def __init__(self, kb: KnowledgeBase, clock, fleet: Fleet, cleanup: Cleanup,
                 config: DispatchConfig):
        self.kb = kb
        self.clock = clock
        self.fleet = fleet
        self.cleanup = cleanup
        self.config = config
        self._wait: dict[int, float] = {}    # robot -> server time it may discard again
        self._fails: dict[int, int] = {}     # robot -> failed discards in a row

    def discard_orphans(self) -> list[M.Task]:
        """Idle robots holding a workpiece no open task will take: discard it."""
        bound = {t.holder for t in self.kb.open_tasks() if t.carry}
        now = self.clock.now()
        out = []
        for r in self.fleet.idle_robots():
            if self._wait.get(r.number, -math.inf) > now:
                continue                     # a discard just failed: not again at once
            if r.holding and r.number not in bound:
                out.append(self.cleanup.discard_for(r))
        return out

    def outcome(self, robot: M.Robot, ok: bool) -> None:
        """Count failed discards in a row and set the robot's wait before the next."""
        if ok:
            self._fails.pop(robot.number, None)
            self._wait.pop(robot.number, None)
            return
        n = self._fails.get(robot.number, 0) + 1
        self._fails[robot.number] = n
        self._wait[robot.number] = self.clock.now() + \
            self.config.discard_backoff * min(2 ** (n - 1), 4)
