"""Real sockets for an agent: the encrypted TCP link to the team server and
the refbox's UDP channels (what ``rll-bt agent`` and multi-process
simulations use; a lockstep simulation passes bus transports instead).

Refbox ports are the robot's view of a port layout (``competition``: one
port per channel; ``sim``: the refbox's split local ports); any of them can
be overridden.
"""
from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

from .. import msgs
from ..agenttask import link as agent_link
from ..clock import Clock
from ..comm import DEFAULT_HOST, TEAM_SERVER_PORT, MessageRegistry, StreamClient, UdpPeer, layout


@dataclass(frozen=True)
class RefboxAddress:
    """Where the refbox's broadcast channels are, from the robot's side.
    ``*_recv``: the port this robot listens on; ``*_send``: where it sends."""
    host: str = DEFAULT_HOST
    layout: str = "competition"
    public_recv: int | None = None
    public_send: int | None = None
    team_recv: int | None = None
    team_send: int | None = None

    def ports(self, channel: str, color: str | None = None) -> tuple[int, int]:
        """(send, recv) for "public" or "team" (then ``color`` "CYAN"/"MAGENTA")."""
        lay = layout(self.layout)
        if channel == "public":
            base = lay.robot("public")
            return self.public_send or base.send, self.public_recv or base.recv
        base = lay.robot(str(color).lower())
        return self.team_send or base.send, self.team_recv or base.recv


def team_server_link(host: str, port: int = TEAM_SERVER_PORT, *, key: str | None, clock: Clock | None = None,
                     backoff_initial: float = 0.2, backoff_max: float = 5.0) -> StreamClient:
    """The agent's end of the team-server link (:mod:`rll_bt.agenttask.link`):
    reconnects with exponential backoff; frames protected with the team key,
    plain for ``key=None`` (a team server of the league)."""
    return agent_link.tcp_client(host, port, key=key, clock=clock, backoff_initial=backoff_initial,
                                 backoff_max=backoff_max)


def refbox_channels(address: RefboxAddress, profile: str, *, key: str,
                    clock: Clock | None = None) -> tuple[UdpPeer, Callable[[str], UdpPeer]]:
    """The public channel (plain, listen only) and a factory for the team
    channel of a colour (encrypted with ``key``)."""
    registry = MessageRegistry.from_message_set(msgs.message_set(profile))
    send, recv = address.ports("public")
    public = UdpPeer(address.host, send, recv, registry=registry, channel="public", clock=clock)

    def team(color: str) -> UdpPeer:
        tsend, trecv = address.ports("team", color)
        return UdpPeer(address.host, tsend, trecv, registry=registry, channel="team", key=key, clock=clock)

    return public, team
