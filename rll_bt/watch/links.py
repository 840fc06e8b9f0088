"""Messages a process sends and receives on its links, on a
:class:`~rll_bt.watch.sink.Watch`: what ``rll-bt agent --record`` and
``rll-bt teamserver --record`` put beside the robot's or server's own channels.

A :class:`WatchedTransport` wraps any transport (UDP peer, TCP stream
client or server, bus end) and shows every message the process sent (once
it left) and every message it received, already decoded, to a
:class:`LinkRecorder`.  Recording what the ends send and receive, not the
wire bytes, is what makes a secured link recordable: the team-server link's
frames are sealed with per-connection keys (:mod:`rll_bt.comm.secure`) that
only the two ends hold.

Topics are the lockstep game's (:mod:`games.watch`):
``/<sender>/<channel>/<Type>`` with the sender ``robotN``, ``teamserver``
or ``refbox`` and the channel ``public``, ``cyan``/``magenta`` (our team
channel) or ``link`` (the team-server link).  Who sent a message that
arrived over UDP is told by the message (:func:`udp_sender`); over the
team-server link it is the other end.
"""
from __future__ import annotations

import re
from collections.abc import Callable
from typing import Any

#: refbox-protocol messages only a team sends (the rest on a refbox channel come from the refbox)
TEAM_SENT = frozenset({"MachineReport", "PrepareMachine", "ResetMachine"})
LINK = "link"


def sender_name(name: str) -> str:
    """A peer's name as a topic segment: ``R2`` -> ``robot2``, ``Team Server`` -> ``team_server``."""
    m = re.fullmatch(r"R(\d+)", name)
    if m:
        return f"robot{m.group(1)}"
    return re.sub(r"[^A-Za-z0-9_]+", "_", name).strip("_").lower() or "unknown"


def udp_sender(msg) -> str:
    """Who sent ``msg`` on a refbox channel, as far as the message tells: a
    beacon names its robot (``peer_name``, else ``R<number>``), a report or
    machine instruction comes from a team server, everything else from the refbox."""
    name = msg.DESCRIPTOR.name
    if name == "BeaconSignal":
        return sender_name(getattr(msg, "peer_name", "") or f"R{getattr(msg, 'number', 0)}")
    return "teamserver" if name in TEAM_SENT else "refbox"


class LinkRecorder:
    """Puts the messages of one process's links on ``watch`` (see the module doc).
    ``me``: this process as a sender (``robot2``, ``teamserver``)."""

    def __init__(self, watch, me: str):
        self.watch = watch
        self.me = me
        self._robots: dict[Any, str] = {}       # stream-server client id -> robotN

    def seen(self, channel: str, sent: bool, msg, source: Any = None) -> None:
        if sent:
            who = self.me
        elif channel == LINK:
            who = self._link_peer(msg, source)
        else:
            who = udp_sender(msg)
        self.watch.proto(f"/{who}/{channel}/{msg.DESCRIPTOR.name}", msg)

    def _link_peer(self, msg, source) -> str:
        if self.me != "teamserver":
            return "teamserver"
        fields = msg.DESCRIPTOR.fields_by_name
        if "robot_id" in fields and msg.HasField("robot_id"):
            self._robots[source] = f"robot{int(msg.robot_id)}"
        return self._robots.get(source, f"client{source}")

    def forget(self, source) -> None:
        self._robots.pop(source, None)

    # -- wrapping ----------------------------------------------------------------------------
    def wrap(self, transport, channel: str) -> WatchedTransport:
        """``transport`` recorded as ``channel`` (``public``, ``cyan``, ``link`` ...)."""
        return WatchedTransport(transport, channel, self)

    def wrap_team(self, factory: Callable[[str], Any]) -> Callable[[str], WatchedTransport]:
        """A team-channel factory (colour -> transport) whose channels are recorded as their colour."""
        def team(color: str) -> WatchedTransport:
            return self.wrap(factory(color), color.lower())
        return team


class WatchedTransport:
    """``inner`` with every message sent and received shown to ``recorder``;
    everything else (events, wait, crypto, stats, close) is ``inner``'s."""

    def __init__(self, inner, channel: str, recorder: LinkRecorder):
        self.inner = inner
        self.watch_channel = channel
        self.recorder = recorder

    def send(self, msg, *args, **kwargs) -> bool:
        ok = self.inner.send(msg, *args, **kwargs)
        if ok:
            self.recorder.seen(self.watch_channel, True, msg)
        return ok

    def receive(self):
        items = self.inner.receive()
        for rx in items:
            self.recorder.seen(self.watch_channel, False, rx.msg, rx.source)
        return items

    def __getattr__(self, name: str) -> Any:
        return getattr(self.inner, name)


__all__ = ["LINK", "LinkRecorder", "TEAM_SENT", "WatchedTransport", "sender_name", "udp_sender"]
