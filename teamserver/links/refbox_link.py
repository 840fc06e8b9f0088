"""The team server's link to the refbox: the public channel plus our team channel.

:class:`RefboxLink` combines a public transport (always there, plain) with a
team transport opened once our colour is known (``set_team``): the factory
gets the colour ("cyan"/"magenta") and returns a transport, which is then
switched to encryption with the team key.  Until then ``send`` has nowhere
to go and returns False.  :func:`udp_refbox_link` builds one over UDP with a
port layout; a lockstep simulation builds one over bus peers.
"""
from __future__ import annotations

from collections.abc import Callable

from rll_bt import msgs
from rll_bt.comm import Layout, MessageRegistry, UdpPeer, layout
from rll_bt.comm.transport import Received, Transport


class RefboxLink:
    def __init__(self, public: Transport, team_factory: Callable[[str], Transport]):
        self.public = public
        self.team_factory = team_factory
        self.team: Transport | None = None
        self.color: str | None = None

    def set_team(self, color: str, key: str | None) -> None:
        """Open the team channel of ``color`` ("CYAN"/"MAGENTA"), encrypted with ``key``."""
        color = color.lower()
        if self.color == color and self.team is not None:
            return
        if self.team is not None:
            self.team.close()
        self.team = self.team_factory(color)
        if key is not None and hasattr(self.team, "set_crypto"):
            self.team.set_crypto(key)
        self.color = color

    def receive(self) -> list[Received]:
        out = list(self.public.receive())
        if self.team is not None:
            out += self.team.receive()
        return out

    def send(self, msg) -> bool:
        """Send on our team channel (False while the colour is unknown)."""
        return self.team.send(msg) if self.team is not None else False

    def close(self) -> None:
        self.public.close()
        if self.team is not None:
            self.team.close()


def udp_refbox_link(profile: str, host: str = "127.0.0.1", port_layout: str | Layout = "sim",
                    clock=None) -> RefboxLink:
    """A RefboxLink over UDP; ``port_layout`` "sim" (split ports), "competition",
    or a :class:`~rll_bt.comm.Layout` (the refbox's view)."""
    reg = MessageRegistry.from_message_set(msgs.message_set(profile))
    lay = port_layout if isinstance(port_layout, Layout) else layout(port_layout)
    pub = lay.robot("public")
    public = UdpPeer(host, pub.send, pub.recv, registry=reg, channel="public", clock=clock)

    def team(color: str) -> Transport:
        ports = lay.robot(color)
        return UdpPeer(host, ports.send, ports.recv, registry=reg, channel="team", clock=clock)

    return RefboxLink(public, team)
