"""The agent's side of the reliable deliveries on the team-server link.

Final task results are kept and repeated until the team server acknowledges
them (also across a reconnect, or while the link is down: sent when it is
back); a task or cancel from the server is acknowledged on every copy.  The
agent acts on every copy: a task it runs or ran is answered with its state
or result, not started again (:class:`~rll_bt.agent.core.RobotAgent` keeps
the results of its last tasks), and a task it turned down (busy) may come
again with the same id.  See :mod:`rll_bt.comm.reliable`.
"""
from __future__ import annotations

from ..comm.reliable import Reliable

SERVER = "teamserver"


class ServerDelivery:
    """``link``: the team-server transport; ``ack(robot)`` -> an empty LinkAck."""

    def __init__(self, link, clock, make_ack, *, retry: float = 1.0):
        self.link = link
        self.reliable = Reliable(clock, retry=retry)
        self.make_ack = make_ack

    def incoming(self, msg) -> bool:
        """Whether the agent should act on ``msg`` (an acknowledgement: no)."""
        if msg.DESCRIPTOR.name == "LinkAck":
            self.reliable.on_ack(SERVER, msg)
            return False
        self.reliable.received(SERVER, msg)     # owe an acknowledgement
        return True

    def send_final(self, result, connected: bool) -> None:
        """A task's final result: sent now if the link is up, kept until acknowledged."""
        self.reliable.track(SERVER, result)
        if connected:
            self.link.send(result)

    def step(self, connected: bool) -> None:
        """Acknowledge what came in, repeat what is due (only while connected)."""
        if not connected:
            return
        for _, ack in self.reliable.acks(lambda _s: self.make_ack()):
            self.link.send(ack)
        for _, msg in self.reliable.due():
            self.link.send(msg)

    def reconnected(self) -> None:
        """The link is back (hello sent): everything unacknowledged, at once."""
        for msg in self.reliable.resend_now(SERVER):
            self.link.send(msg)

    @property
    def unacknowledged(self) -> list:
        return self.reliable.pending(SERVER)

