"""The agent's end of the team-server link: who the robot is, that it lives, what it did.

Every ``heartbeat_period`` the robot sends a ``BeaconSignal`` (rcll2025:
number, team, name, colour, pose, the task it runs in field 9 and its last
finished tasks in field 10), as the league's robots do; results go out as
the league's echoed ``AgentTask``.  Towards an rll-bt team server it also
says ``RobotHello`` on every connect, ``RobotStatus`` every
``status_period`` and on every change, and ``TaskOutcome`` before each
result (see :mod:`rll_bt.agenttask`).  With ``league_only`` it says nothing
but the league's messages, and does not take a silent server for a lost one
(a league team server speaks only when it has a task).

Towards an rll-bt team server final results are delivered reliably
(:mod:`rll_bt.agent.delivery`): kept until the server acknowledges them
(``LinkAck``), repeated meanwhile and at once when the link is back; the
server's tasks and cancels are acknowledged.  A league team server knows no
``LinkAck``: its results that cannot go out while the link is down wait in
an outbox and go first once it is back.
"""
from __future__ import annotations

import logging
import math
from collections import deque
from collections.abc import Callable, Iterable

from .. import msgs
from ..backend import Pose2D
from ..clock import Clock
from ..comm import CONNECTED, DISCONNECTED
from .config import AgentConfig
from .delivery import ServerDelivery
from .lease import TaskLease
from .taskbook import Result

log = logging.getLogger("rll_bt.agent")


def stamp_time(msg, clock: Clock) -> None:
    """Set a ``llsf_msgs.Time`` to the clock's epoch."""
    t = clock.epoch()
    sec = math.floor(t)
    msg.sec, msg.nsec = int(sec), int(round((t - sec) * 1e9)) % 1_000_000_000


class ServerLink:
    """See the module doc.  ``transport``: the link (a stream client);
    ``restarted``: the first RobotHello says the robot lost its state."""

    def __init__(self, transport, config: AgentConfig, clock: Clock, *, restarted: bool = True):
        self.t = transport
        self.config = config
        self.clock = clock
        self.league_only = bool(config.league_only)
        self.lm = msgs.message_set("rcll2025")
        self.tm = msgs.message_set("team")
        self.connected = False
        self.registrations = 0
        self.last_rx: float | None = None
        self.silent = False
        self.outbox: deque[Result] = deque(maxlen=256)          # league_only: results awaiting the link
        self.delivery = None if self.league_only else ServerDelivery(
            lambda m: bool(self.t.send(m)), clock, lambda: self.tm.LinkAck(robot_id=config.robot_id))
        self._restarted_next = restarted
        self._hello_due = bool(getattr(transport, "connected", False))
        self.seq = 0
        self.server_speaks_rllbt = False      # a GamePhase / MachineMap / TaskDetail came
        self.color: str | None = None         # our colour, set by the agent once known
        self.lease = TaskLease()              # how long the server leaves the robot its task unheard

    @property
    def extras(self) -> bool:
        """Whether rll-bt's additions go out on this link."""
        return not self.league_only

    # -- receiving ---------------------------------------------------------------------------
    def poll(self, on_connect: Callable[[], None]) -> list:
        """Link events and the messages that arrived; ``on_connect()`` runs once the
        robot has (re)introduced itself."""
        for ev in self.t.events():
            if ev.kind == CONNECTED:
                self.connected = True
                self._hello_due = True
                log.info("robot %d: connected to the team server", self.config.robot_id)
            elif ev.kind == DISCONNECTED:
                self.connected = False
                self._hello_due = False
                log.warning("robot %d: team server link lost; reconnecting", self.config.robot_id)
        if self._hello_due and getattr(self.t, "connected", True):
            self._introduce(on_connect)
        out = []
        for rec in self.t.receive():
            self.last_rx = self.clock.now()
            self.silent = False
            if rec.msg.DESCRIPTOR.full_name.startswith("rllbt."):
                self.server_speaks_rllbt = True
                self.lease.heard(rec.msg, self.last_rx)
            if self.delivery is not None and not self.delivery.incoming(rec.msg):
                continue                        # an acknowledgement
            out.append(rec)
        return out

    def _introduce(self, on_connect) -> None:
        c = self.config
        if self.extras:
            hello = self.tm.RobotHello(robot_id=c.robot_id, team_name=c.team_name, peer_name=c.peer_name,
                                       capabilities=list(c.capabilities), restarted=self._restarted_next)
            if self.color:
                hello.team_color = self.tm.enum("TeamColor").Value(self.color)
            if not self.t.send(hello):
                return
        self.connected = True
        self._hello_due = False
        self._restarted_next = False
        self.registrations += 1
        self.last_rx = self.clock.now()
        on_connect()
        if self.delivery is not None:
            self.delivery.reconnected()         # final results the server has not acknowledged
        while self.outbox:
            if not self._send_result(self.outbox[0]):
                break
            self.outbox.popleft()

    # -- sending ------------------------------------------------------------------------------
    def send(self, msg) -> bool:
        return bool(self.connected and self.t.send(msg))

    def send_extra(self, msg) -> bool:
        """An rll-bt addition (nothing goes out in league-only mode)."""
        return self.extras and self.send(msg)

    def result(self, result: Result) -> None:
        """Send a task's final result, and keep it until the server acknowledges it
        (a league server: until it could be sent)."""
        if self.delivery is not None:
            self.delivery.send_final(result.task, self.connected, before=[result.outcome])
        elif not (self.connected and self._send_result(result)):
            self.outbox.append(result)

    def again(self, result: Result) -> None:
        """Tell a result once more (the server sent its task again)."""
        if self.delivery is None:
            self.result(result)
        elif self.connected:
            self._send_result(result)

    def step(self) -> None:
        """Acknowledgements owed and results due again (rll-bt team server)."""
        if self.delivery is not None:
            self.delivery.step(self.connected)

    def _send_result(self, result: Result) -> bool:
        if self.extras and not self.t.send(result.outcome):
            return False
        return bool(self.t.send(result.task))

    def beacon(self, pose: Pose2D | None, task, finished: Iterable[tuple[int, bool]]):
        """The robot's BeaconSignal (rcll2025) as it is now."""
        c = self.config
        self.seq += 1
        b = self.lm.BeaconSignal(seq=self.seq, number=c.robot_id, team_name=c.team_name, peer_name=c.peer_name)
        stamp_time(b.time, self.clock)
        if self.color:
            b.team_color = self.lm.enum("Team").Value(self.color)
        if pose is not None:
            stamp_time(b.pose.timestamp, self.clock)
            b.pose.x, b.pose.y, b.pose.ori = pose.x, pose.y, pose.theta
        if task is not None:
            b.task.CopyFrom(task)
        for task_id, ok in finished:
            b.finished_tasks.add(TaskId=int(task_id), successful=bool(ok))
        return b

    def status_msg(self, state: str, pose: Pose2D | None, confidence: float, task_id: int | None,
                   holding: bool, battery=None):
        """rll-bt's RobotStatus (``battery``: the backend's Battery, or None)."""
        st = self.tm.RobotStatus(robot_id=self.config.robot_id, state=self.tm.RobotStatus.State.Value(state),
                                 stamp=self.clock.now())
        if pose is not None:
            st.pose.x, st.pose.y, st.pose.theta = pose.x, pose.y, pose.theta
            st.pose_confidence = confidence
        if task_id is not None:
            st.current_task_id = task_id
        if holding:
            st.holding.SetInParent()
        if self.lease.lag is not None:
            st.lease_lag = self.lease.lag       # the server lengthens the lease by it (.lease)
        if battery is not None:
            st.battery_voltage = battery.voltage
            if battery.soc is not None:
                st.battery_fraction = battery.soc
        return st

    def check_silence(self, now: float) -> None:
        """Reconnect when an rll-bt team server has said nothing for ``server_timeout``."""
        if self.league_only or not self.connected or self.last_rx is None or self.silent:
            return
        if now - self.last_rx > self.config.server_timeout:
            self.silent = True
            log.warning("robot %d: nothing from the team server for %.1f s; reconnecting",
                        self.config.robot_id, now - self.last_rx)
            reconnect = getattr(self.t, "reconnect", None)
            if reconnect is not None:
                reconnect()

    def wait(self, seconds: float) -> None:
        self.t.wait(seconds)

    def close(self) -> None:
        self.t.close()
