"""The team-server link's messages and transports, built in one place.

The link carries protobuf_comm frames (the refbox's v2 frames) over TCP, or
the in-process bus in lockstep games.  Its messages: the league's
``AgentTask`` (8000/502, both ways) and ``BeaconSignal`` (2000/1, robot to
server, with the current task in field 9 and the finished ones in field
10), both from the rcll2025 set whatever the rules profile, and rll-bt's
additions (package ``rllbt``, COMP_ID 3000; :data:`EXTRAS`).

How the frames are protected is decided here and nowhere else
(:func:`crypto`): with the team key between rll-bt's own team server and
agents, plain between peers of the league (the league's simulator and the
team servers that drive it send plain frames).  Every transport of the
link is made by the functions below, so a change of the link's encryption
touches this module only.
"""
from __future__ import annotations

from collections.abc import Callable
from typing import Any

from .. import msgs
from ..comm import MessageRegistry, StreamClient, StreamServer

#: the league's messages of the link (rcll2025 set)
LEAGUE = ("AgentTask", "WorkpieceDescription", "BeaconSignal")
#: rll-bt's additions, exchanged only between peers that both speak them
EXTRAS = ("RobotHello", "Heartbeat", "RobotStatus", "TaskDetail", "TaskOutcome", "MachineObservation",
          "ZoneExplored", "MachineMap", "GamePhase", "LinkAck")
#: what every side calls the link's channel
CHANNEL = "teamserver"

_REGISTRY: MessageRegistry | None = None


def registry() -> MessageRegistry:
    """The messages of the link: the league's (:data:`LEAGUE`) and rll-bt's (:data:`EXTRAS`)."""
    global _REGISTRY
    if _REGISTRY is None:
        lm, tm = msgs.message_set("rcll2025"), msgs.message_set("team")
        reg = MessageRegistry([lm.get(n) for n in LEAGUE])
        reg.add_all(tm.classes.values())
        _REGISTRY = reg
    return _REGISTRY


def league_registry() -> MessageRegistry:
    """Only the league's messages of the link (what a peer of the league understands)."""
    lm = msgs.message_set("rcll2025")
    return MessageRegistry([lm.get(n) for n in LEAGUE])


def crypto(key: str | None) -> dict[str, Any]:
    """Transport keyword arguments protecting the link: frames encrypted with
    the team ``key``, or plain frames for ``None`` (a league peer)."""
    return {"key": key or None}


def tcp_server(port: int, *, key: str | None, host: str = "0.0.0.0", clock=None,
               cls: Callable[..., StreamServer] = StreamServer, **kw) -> StreamServer:
    """The team server's end over TCP (``cls``: a StreamServer subclass, e.g. one that logs)."""
    return cls(port, host=host, registry=registry(), clock=clock, **crypto(key), **kw)


def tcp_client(host: str, port: int, *, key: str | None, clock=None, channel: str = CHANNEL,
               **kw) -> StreamClient:
    """A robot's end over TCP: reconnects with exponential backoff."""
    return StreamClient(host, port, registry=registry(), clock=clock, channel=channel, **crypto(key), **kw)


def bus_server(bus, address: str = CHANNEL, *, key: str | None):
    """The team server's end on the in-process bus (lockstep games)."""
    return bus.stream_server(address, registry=registry(), **crypto(key))


def bus_client(bus, address: str = CHANNEL, *, key: str | None, name: str = ""):
    """A robot's end on the in-process bus."""
    return bus.stream_client(address, registry=registry(), name=name, **crypto(key))
