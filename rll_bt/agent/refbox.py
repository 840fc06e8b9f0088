"""The agent's side of the refbox: the public channel (listen only) and the
team's encrypted channel (beacons; MachineInfo for a robot that finds the
stations itself).

Robots send only on their own team channel and never on the other team's
(refbox-protocol §2), so the team channel opens once the colour is known.
``team`` is either a transport already bound to the right channel, or a
factory ``team(color) -> transport`` ("CYAN"/"MAGENTA") called when the
colour becomes known or changes; the transport encrypts with the team key.

BeaconSignal: ``time`` is the clock's epoch (UTC seconds), ``seq``
increases per beacon, ``number`` is the jersey, ``pose`` the field pose
(m, rad).  With the rcll2025 message set it also carries the current task
(the ``AgentTask`` the robot got) and the last finished tasks.
"""
from __future__ import annotations

import logging
import math
from collections.abc import Callable, Iterable
from typing import Any

from ..backend import Pose2D
from ..clock import Clock
from ..comm import Received

log = logging.getLogger("rll_bt.agent")

TeamChannel = Any   # a Transport, or Callable[[str], Transport]


class RefboxLink:
    def __init__(self, ms, clock: Clock, robot_id: int, team_name: str, peer_name: str,
                 public=None, team: TeamChannel | None = None):
        self.ms = ms
        self.clock = clock
        self.robot_id, self.team_name, self.peer_name = robot_id, team_name, peer_name
        self.public = public
        self._factory: Callable[[str], Any] | None = None
        self.team = None
        if callable(team) and not hasattr(team, "send"):
            self._factory = team
        else:
            self.team = team
        self.color: str | None = None
        self.seq = 0
        self.beacons_sent = 0

    def set_color(self, color: str) -> None:
        """Our colour is known (or changed): open that team channel if we make our own."""
        if color == self.color:
            return
        self.color = color
        if self._factory is not None:
            if self.team is not None:
                self.team.close()
            self.team = self._factory(color)
            log.info("refbox team channel: %s", color.lower())

    def receive(self) -> list[Received]:
        """Everything that arrived on the public and team channels."""
        out: list[Received] = []
        for t in (self.public, self.team):
            if t is not None:
                out.extend(t.receive())
        return out

    # -- sending --------------------------------------------------------------------
    def _time(self, msg) -> None:
        t = self.clock.epoch()
        sec = math.floor(t)
        msg.sec, msg.nsec = int(sec), int(round((t - sec) * 1e9)) % 1_000_000_000

    def beacon(self, pose: Pose2D | None, task=None, finished: Iterable[tuple[int, bool]] = ()) -> bool:
        """Send one BeaconSignal on the team channel; False when it cannot go
        out (no colour or team channel yet, or the transport refused it)."""
        if self.team is None or self.color is None:
            return False
        self.seq += 1
        b = self.ms.BeaconSignal(seq=self.seq, number=self.robot_id, team_name=self.team_name,
                                 peer_name=self.peer_name, team_color=self.ms.enum("Team").Value(self.color))
        self._time(b.time)
        if pose is not None:
            self._time(b.pose.timestamp)
            b.pose.x, b.pose.y, b.pose.ori = pose.x, pose.y, pose.theta
        fields = b.DESCRIPTOR.fields_by_name
        if task is not None and "task" in fields:
            b.task.CopyFrom(task)
        if "finished_tasks" in fields:
            for task_id, ok in finished:
                b.finished_tasks.add(TaskId=int(task_id), successful=bool(ok))
        sent = bool(self.team.send(b))
        self.beacons_sent += sent
        return sent

    def close(self) -> None:
        for t in (self.public, self.team):
            if t is not None:
                t.close()
