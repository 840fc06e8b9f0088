"""Where a robot of the league waits, read from its beacons.

Under rules that break a station left PREPARED too long before its
workpiece comes (2025: 20 s), rll-bt's team server prepares a feed's
station only once the feed's robot waits there, docked
(:mod:`teamserver.dispatch.prepare`).  rll-bt's agents say so (RobotStatus
``waiting_at``); a robot of the league says nothing but its BeaconSignal:
its pose and the task it runs (field 9).  :class:`Docking` reads the same
from them: the robot runs the current assignment of a feed (a task with a
PrepareMachine), stands within ``near`` metres of that station (its
fused pose, else its zone's centre, as the refbox reveals it) and has
not moved more than ``still`` metres or turned more than ``turn`` radians
for ``settle`` seconds: it waits there, docked (a robot of the league, like
rll-bt's trees, puts its workpiece once the station shows prepared).
"""
from __future__ import annotations

import math

from ..knowledge import model as M
from ..knowledge.kb import KnowledgeBase


class Docking:
    """See the module doc."""

    def __init__(self, kb: KnowledgeBase, clock, *, near: float = 1.6, still: float = 0.02,
                 turn: float = 0.02, settle: float = 2.0):
        self.kb = kb
        self.clock = clock
        self.near, self.still, self.turn, self.settle = near, still, turn, settle
        self._since: dict[int, tuple[float, tuple[float, float, float], int]] = {}   # robot -> (t, pose, wire)

    def waiting_at(self, number: int, pose: tuple[float, float, float] | None, wire: int | None,
                   task: M.Task | None) -> str | None:
        """The station robot ``number`` waits at, docked, from its beacon now:
        ``pose`` (x, y, ori), ``wire`` the id of the AgentTask it runs (None:
        none), ``task`` the server's task of that assignment (None: not ours)."""
        if pose is None or wire is None or task is None or not task.prepare:
            self._since.pop(number, None)
            return None
        machine = task.prepare["machine"]
        where = self.kb.machine_position(machine)      # its fused pose, else its zone's centre
        if where is None or math.hypot(where[0] - pose[0], where[1] - pose[1]) > self.near:
            self._since.pop(number, None)
            return None
        now = self.clock.now()
        since = self._since.get(number)
        if since is None or since[2] != wire or self._moved(since[1], pose):
            self._since[number] = (now, pose, wire)
            return None
        return machine if now - since[0] >= self.settle else None

    def _moved(self, a, b) -> bool:
        turned = abs(math.remainder(a[2] - b[2], math.tau))
        return math.hypot(a[0] - b[0], a[1] - b[1]) > self.still or turned > self.turn
