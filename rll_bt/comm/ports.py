"""Refbox network layouts (refbox-protocol §2).

Three UDP broadcast channels, public (plain), cyan and magenta (each team's
AES-128-CBC channel), and the refbox's TCP stream for controllers.

- :data:`COMPETITION`: one port per channel for sending and listening
  (public 4444, cyan 4441, magenta 4442).
- :data:`SIM`: the refbox's default local config with split ports so several
  processes on one host can talk: the refbox sends to 4444/4441/4442 and
  listens on 4445/4446/4447; a robot listens on the former and sends to the
  latter.

Ports are given from the refbox's side; :meth:`Layout.robot` swaps them for a
robot (or the monitor).
"""
from __future__ import annotations

import socket
from dataclasses import dataclass

PUBLIC, CYAN, MAGENTA = "public", "cyan", "magenta"
CHANNELS = (PUBLIC, CYAN, MAGENTA)
TEAM_COLORS = (CYAN, MAGENTA)

#: refbox's TCP stream port (controllers only; robots must not use it)
REFBOX_STREAM_PORT = 4444
#: default host of the refbox's peers (its default config)
DEFAULT_HOST = "127.0.0.1"
#: default TCP port of the team server <-> robot link (our choice, clear of 4441-4447)
TEAM_SERVER_PORT = 4460


@dataclass(frozen=True)
class PeerPorts:
    """The ports one UDP peer uses: sends to ``send``, binds and listens on ``recv``."""

    send: int
    recv: int

    @property
    def split(self) -> bool:
        return self.send != self.recv

    def swapped(self) -> PeerPorts:
        return PeerPorts(send=self.recv, recv=self.send)


@dataclass(frozen=True)
class Layout:
    """Port layout, refbox's view.  ``stream`` is the refbox TCP port."""

    name: str
    public: PeerPorts
    cyan: PeerPorts
    magenta: PeerPorts
    stream: int = REFBOX_STREAM_PORT

    def refbox(self, channel: str) -> PeerPorts:
        """The refbox's ports for ``channel`` ("public", "cyan", "magenta")."""
        if channel not in CHANNELS:
            raise ValueError(f"unknown channel {channel!r}; one of {', '.join(CHANNELS)}")
        return getattr(self, channel)

    def robot(self, channel: str) -> PeerPorts:
        """A robot's ports for ``channel``: it listens where the refbox sends."""
        return self.refbox(channel).swapped()

    def moved(self, offset: int) -> Layout:
        """This layout with every port (and the stream) ``offset`` higher, named ``NAME+offset``."""
        if not offset:
            return self

        def shift(pp: PeerPorts) -> PeerPorts:
            return PeerPorts(pp.send + offset, pp.recv + offset)
        return Layout(f"{self.name}+{offset}", shift(self.public), shift(self.cyan), shift(self.magenta),
                      self.stream + offset)


COMPETITION = Layout("competition", public=PeerPorts(4444, 4444), cyan=PeerPorts(4441, 4441),
                     magenta=PeerPorts(4442, 4442))
SIM = Layout("sim", public=PeerPorts(send=4444, recv=4445), cyan=PeerPorts(send=4441, recv=4446),
             magenta=PeerPorts(send=4442, recv=4447))
LAYOUTS = {COMPETITION.name: COMPETITION, SIM.name: SIM}


def layout(name: str) -> Layout:
    try:
        return LAYOUTS[name]
    except KeyError:
        raise ValueError(f"unknown port layout {name!r}; one of {', '.join(LAYOUTS)}") from None


def free_ports(count: int, tcp: bool = False, host: str = "127.0.0.1") -> list[int]:
    """``count`` distinct UDP (or TCP) ports the system has free right now (bound and released)."""
    socks, ports = [], []
    try:
        for _ in range(count):
            s = socket.socket(socket.AF_INET, socket.SOCK_STREAM if tcp else socket.SOCK_DGRAM)
            s.bind((host, 0))
            socks.append(s)
            ports.append(s.getsockname()[1])
    finally:
        for s in socks:
            s.close()
    return ports
