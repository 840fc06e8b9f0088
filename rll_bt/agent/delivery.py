"""The agent's side of the reliable deliveries on the team-server link.

Final task results (the league's AgentTask echoed with ``successful`` /
``canceled``) are kept and repeated until the team server acknowledges them
(also across a reconnect, or while the link is down: sent when it is back),
each copy after the messages that go with it (rll-bt's TaskOutcome); a task
or cancel from the server is acknowledged on every copy.  The agent acts on
every copy: a task it runs or ran is not started again, a finished one is
answered with its result (:class:`~rll_bt.agent.taskbook.TaskBook`).  Only
towards an rll-bt team server: a league team server knows no ``LinkAck``.
See :mod:`rll_bt.comm.reliable`.
"""
from __future__ import annotations

from collections.abc import Callable, Sequence

from ..comm.reliable import Reliable

SERVER = "teamserver"


class ServerDelivery:
    """``send(msg) -> bool``: onto the team-server link; ``make_ack()`` -> an empty LinkAck."""

    def __init__(self, send: Callable[[object], bool], clock, make_ack, *, retry: float = 1.0):
        self.send = send
        self.reliable = Reliable(clock, retry=retry)
        self.make_ack = make_ack
        self._before: dict = {}          # link key -> the messages that go just before that one

    def incoming(self, msg) -> bool:
        """Whether the agent should act on ``msg`` (an acknowledgement: no)."""
        if msg.DESCRIPTOR.name == "LinkAck":
            self.reliable.on_ack(SERVER, msg)
            self._prune()
            return False
        self.reliable.received(SERVER, msg)     # owe an acknowledgement
        return True

    def send_final(self, msg, connected: bool, before: Sequence = ()) -> None:
        """A task's final result ``msg``, after ``before``: sent now if the link is
        up, kept (and repeated with ``before``) until acknowledged."""
        if self.reliable.track(SERVER, msg) and before:
            self._before[self.reliable.key(msg)] = list(before)
        if connected:
            self._send(msg)

    def _send(self, msg) -> bool:
        for m in self._before.get(self.reliable.key(msg), ()):
            if not self.send(m):
                return False
        return self.send(msg)

    def step(self, connected: bool) -> None:
        """Acknowledge what came in, repeat what is due (only while connected)."""
        if not connected:
            return
        for _, ack in self.reliable.acks(lambda _s: self.make_ack()):
            self.send(ack)
        for _, msg in self.reliable.due():
            self._send(msg)

    def reconnected(self) -> None:
        """The link is back (the robot introduced itself): everything unacknowledged, at once."""
        for msg in self.reliable.resend_now(SERVER):
            self._send(msg)

    def _prune(self) -> None:
        if len(self._before) > len(self.reliable.pending(SERVER)):
            live = {self.reliable.key(m) for m in self.reliable.pending(SERVER)}
            for k in [k for k in self._before if k not in live]:
                del self._before[k]

    @property
    def unacknowledged(self) -> list:
        return self.reliable.pending(SERVER)
