"""The simulated refbox on the wire: a :class:`RefboxGame` behind the refbox's channels.

Channels (refbox-protocol §2): ``public`` (plain), one channel per team
colour (AES-128-CBC with the key of the team playing that colour, plain while
no team or no key is set), and optionally the controller stream (plain).
They are any :class:`rll_bt.comm.Transport`: UDP peers and a TCP server
(:meth:`RefboxNode.on_udp`) or in-process bus endpoints
(:meth:`RefboxNode.on_bus`, lockstep).

:meth:`RefboxNode.step` is the whole loop body: take every message that
arrived, hand it to the game, tick the game, send what is due.  What goes
out, when (clock seconds; the refbox's globals.clp and net.clp):

==================  =================  ===========================================
message             channel            when
==================  =================  ===========================================
BeaconSignal        public             1 s (team "LLSF", peer "RefBox", number 0)
GameState           public + stream    1 s
VersionInfo         public             0.5 s x10 at start and after a new peer
RobotInfo           public / stream    2.5 s / 0.25 s
ExplorationInfo     public             1 s in EXPLORATION (2016 only)
MachineReportInfo   cyan, magenta      1 s while reports are taken (2016: EXPLORATION;
                                       2025: PRODUCTION before the exploration time)
OrderInfo           public + stream    PRODUCTION: 0.5 s x10, then 2 s; the burst
                                       restarts on a new order and on a delivery
MachineInfo         cyan, magenta      PRODUCTION: 0.5 s x30, then 2 s, and at once
                                       when a machine of that team changes state or
                                       (2025) a report or the ground truth reveals one
MachineInfo (all)   stream             0.25 s (with every zone and rotation)
RingInfo            cyan + magenta     PRODUCTION: 2 s
AttentionMessage    team's channel     when the game raises one (always on stream)
==================  =================  ===========================================

Accepted: BeaconSignal (any channel), MachineReport, PrepareMachine and
ResetMachine (2025) on a team channel (the team colour must match the
channel) or the stream,
SetGameState, SetGamePhase and SetTeamName on the stream (and on public with
``control_via_public``, the refbox's ``control-via-broadcast``); SimTimeSync
on the stream when the game's clock follows it (``time-sync``).  Anything
else is counted in :attr:`ignored` and dropped; a message that makes the
game raise is logged and dropped, never fatal.
"""
from __future__ import annotations

import logging
from collections import Counter
from dataclasses import dataclass, field

from rll_bt.comm import MessageRegistry
from rll_bt.rules import CYAN, MAGENTA, TEAMS

from . import events as E
from .messages import Messages, enum_name, sent_at
from .world import WorldLost

log = logging.getLogger("backends.sim.refbox.node")

PUBLIC, STREAM = "public", "stream"


class Periodic:
    """A send schedule: every ``period`` s after ``burst_count`` sends ``burst_period`` apart.
    ``period`` None stops after the burst.  Due at once after :meth:`restart`."""

    def __init__(self, period: float | None, burst_period: float | None = None,
                 burst_count: int = 0):
        self.period, self.burst_period, self.burst_count = period, burst_period, burst_count
        self.count = 0
        self.next: float | None = None

    def restart(self) -> None:
        self.count, self.next = 0, None

    def due(self, now: float) -> bool:
        if self.next is not None and now < self.next - 1e-9:
            return False
        if self.next is None and self.count > 0:      # a burst-only schedule that ended
            return False
        self.count += 1
        gap = self.burst_period if self.count < self.burst_count else self.period
        if self.count == self.burst_count and self.period is None:
            gap = None
        self.next = None if gap is None else now + gap
        return True


@dataclass
class Channels:
    """The refbox's transports: ``public``, ``team`` by colour, optional ``stream`` server."""

    public: object
    team: dict = field(default_factory=dict)
    stream: object | None = None

    def all(self):
        yield PUBLIC, None, self.public
        for color, t in self.team.items():
            yield color.lower(), color, t
        if self.stream is not None:
            yield STREAM, None, self.stream

    def close(self) -> None:
        for _label, _team, t in self.all():
            try:
                t.close()
            except Exception:
                log.debug("closing %s failed", t, exc_info=True)


class RefboxNode:
    """``game`` on ``channels``.  ``keys``: team name -> crypto key (the refbox's
    ``llsfrb/game/crypto-keys``); a colour's channel is encrypted with the key of
    the team playing it."""

    def __init__(self, game, channels: Channels, *, keys: dict[str, str] | None = None,
                 control_via_public: bool = False):
        self.game = game
        self.clock = game.clock
        self.channels = channels
        self.keys = dict(keys or {})
        self.control_via_public = control_via_public
        self.messages = Messages(game.profile.name)
        self._crypto: dict[str, str | None] = {}
        self._ev = len(game.events)
        self._rng = game.rng("exploration-info-order")
        self.sent: Counter = Counter()
        self.received: Counter = Counter()
        self.ignored: Counter = Counter()
        self.beacon = Periodic(1.0)
        self.gamestate = Periodic(1.0)
        self.version = Periodic(None, 0.5, 10)
        self.robot_info_public = Periodic(2.5)
        self.robot_info_stream = Periodic(0.25)
        self.exploration_info = Periodic(1.0)
        self.report_info = Periodic(1.0)
        self.order_info = Periodic(2.0, 0.5, 10)
        self.machine_info = Periodic(2.0, 0.5, 30)
        self.machine_info_stream = Periodic(0.25)
        self.ring_info = Periodic(2.0)
        self._apply_crypto()

    # -- construction ------------------------------------------------------------
    @staticmethod
    def registry(game) -> MessageRegistry:
        return MessageRegistry.from_message_set(Messages(game.profile.name).ms)

    @classmethod
    def on_bus(cls, game, bus, *, keys: dict[str, str] | None = None,
               stream_address: str | None = "refbox", control_via_public: bool = False,
               channel_names: dict[str, str] | None = None) -> RefboxNode:
        """The refbox on an in-process :class:`rll_bt.comm.Bus` (lockstep).  Robots join
        bus channels "public", "cyan" and "magenta" (``channel_names`` renames them);
        controllers connect a stream client to ``stream_address``."""
        reg = cls.registry(game)
        names = {PUBLIC: PUBLIC, CYAN: "cyan", MAGENTA: "magenta", **(channel_names or {})}
        ch = Channels(public=bus.peer(names[PUBLIC], registry=reg, name="refbox", label=PUBLIC),
                      team={c: bus.peer(names[c], registry=reg, name="refbox", label=c.lower())
                            for c in TEAMS})
        if stream_address:
            ch.stream = bus.stream_server(stream_address, registry=reg, channel=STREAM)
        return cls(game, ch, keys=keys, control_via_public=control_via_public)

    @classmethod
    def on_udp(cls, game, *, host: str = "127.0.0.1", layout="sim",
               keys: dict[str, str] | None = None, stream_port: int | None = None,
               stream_host: str = "0.0.0.0", bind_host: str = "0.0.0.0",
               control_via_public: bool = False) -> RefboxNode:
        """The refbox on UDP: ``layout`` (a :class:`rll_bt.comm.Layout` or its name,
        "competition" or "sim") gives each channel's send and receive ports from the
        refbox's side; ``stream_port`` (default the layout's, 0 = ephemeral, -1 = none)
        is the plain TCP control stream.  Raises OSError if a port is taken."""
        from rll_bt.comm import Layout, StreamServer, UdpPeer
        from rll_bt.comm import layout as get_layout
        lay = layout if isinstance(layout, Layout) else get_layout(layout)
        reg = cls.registry(game)
        opened = []
        try:
            def peer(chan: str, label: str):
                ports = lay.refbox(chan)
                p = UdpPeer(host, ports.send, ports.recv, registry=reg, channel=label,
                            bind_host=bind_host, clock=game.clock)
                opened.append(p)
                return p
            ch = Channels(public=peer("public", PUBLIC),
                          team={c: peer(c.lower(), c.lower()) for c in TEAMS})
            port = lay.stream if stream_port is None else stream_port
            if port is not None and port >= 0:
                ch.stream = StreamServer(port, registry=reg, host=stream_host, clock=game.clock,
                                         channel=STREAM)
        except Exception:
            for p in opened:
                p.close()
            raise
        return cls(game, ch, keys=keys, control_via_public=control_via_public)

    def close(self) -> None:
        self.channels.close()

    def tap(self, fn) -> None:
        """Call ``fn(channel, source, message)`` for every message sent ("refbox" the
        source) or received from now on; ``channel``: "public", "cyan", "magenta", "stream"."""
        ch = self.channels
        ch.public = _Tapped(ch.public, PUBLIC, fn)
        ch.team = {color: _Tapped(t, color.lower(), fn) for color, t in ch.team.items()}
        if ch.stream is not None:
            ch.stream = _Tapped(ch.stream, STREAM, fn)

    # -- the loop body -------------------------------------------------------------
    def step(self) -> None:
        """Receive and handle everything, tick the game, send what is due."""
        for label, team, transport in self.channels.all():
            for rec in transport.receive():
                self._handle(rec, label, team)
            for ev in transport.events():
                if ev.kind == "connected":
                    self.version.restart()
        self.game.tick()
        self._apply_crypto()
        self._react()
        self._send_periodic(self.clock.now())

    # -- incoming ------------------------------------------------------------------
    def _handle(self, rec, label: str, team: str | None) -> None:
        name = rec.msg.DESCRIPTOR.name
        self.received[name] += 1
        try:
            handler = getattr(self, f"_on_{name}", None)
            if handler is None or not handler(rec.msg, rec, label, team):
                self.ignored[name] += 1
        except WorldLost:
            raise
        except Exception:
            self.ignored[name] += 1
            log.exception("%s on %s could not be handled", name, label)

    def _on_BeaconSignal(self, msg, rec, label, team) -> bool:
        pose = (msg.pose.x, msg.pose.y, msg.pose.ori) if msg.HasField("pose") else None
        src = rec.source
        host = src[0] if isinstance(src, tuple) else str(src)
        self.game.beacon(number=msg.number, team_name=msg.team_name, peer_name=msg.peer_name,
                         pose=pose, host=host, team_color=enum_name(msg, "team_color"))
        return True

    def _on_MachineReport(self, msg, rec, label, team) -> bool:
        if label == PUBLIC:
            return False
        color, entries = Messages.report(msg)
        self.game.machine_report(color, entries, channel_team=team)
        return True

    def _on_PrepareMachine(self, msg, rec, label, team) -> bool:
        if label == PUBLIC:
            return False
        machine = msg.machine
        instr = Messages.prepare(msg, machine[2:4] if len(machine) >= 4 else "")
        self.game.prepare(enum_name(msg, "team_color"), machine, instr, channel_team=team,
                          sent_at=sent_at(msg))
        return True

    def _on_ResetMachine(self, msg, rec, label, team) -> bool:
        if label == PUBLIC:
            return False
        self.game.reset_machine(enum_name(msg, "team_color"), msg.machine, channel_team=team)
        return True

    def _control_allowed(self, label: str) -> bool:
        return label == STREAM or (label == PUBLIC and self.control_via_public)

    def _control(self, label: str, value, apply) -> bool:
        """Apply an operator command if it came on a control channel."""
        if not self._control_allowed(label) or value is None:
            return False
        try:
            return apply(value) is not False
        except ValueError as exc:        # e.g. SetGamePhase EXPLORATION for rcll2025
            log.warning("operator command refused: %s", exc)
            return False

    def _on_SetGameState(self, msg, rec, label, team) -> bool:
        return self._control(label, enum_name(msg, "state"), self.game.set_state)

    def _on_SetGamePhase(self, msg, rec, label, team) -> bool:
        return self._control(label, enum_name(msg, "phase"), self.game.set_phase)

    def _on_SimTimeSync(self, msg, rec, label, team) -> bool:
        """A simulation's time (``time-sync``): the game's clock follows it when it can
        (a :class:`~rll_bt.clock.SyncedClock`); taken on the stream only."""
        sync = getattr(self.clock, "sync", None)
        if label != STREAM or sync is None:
            return False
        sync(msg.sim_time.sec + msg.sim_time.nsec / 1e9, msg.real_time_factor, msg.paused)
        return True

    def _on_SetTeamName(self, msg, rec, label, team) -> bool:
        return self._control(label, enum_name(msg, "team_color"),
                             lambda color: self.game.set_team(color, msg.team_name))

    # -- crypto ----------------------------------------------------------------------
    def _apply_crypto(self) -> None:
        for color, transport in self.channels.team.items():
            name = self.game.teams.get(color)
            key = self.keys.get(name) if name else None
            if self._crypto.get(color, "unset") == key:
                continue
            self._crypto[color] = key
            if key:
                transport.set_crypto(key)
            else:
                transport.clear_crypto()
                if name:
                    log.warning("no crypto key for team %s: the %s channel stays plain",
                                name, color.lower())

    # -- outgoing --------------------------------------------------------------------
    def _send(self, transport, msg) -> None:
        if transport is None:
            return
        try:
            if transport.send(msg):
                self.sent[msg.DESCRIPTOR.name] += 1
        except Exception as exc:
            log.error("cannot send %s on %s: %s", msg.DESCRIPTOR.name,
                      getattr(transport, "channel", "?"), exc)

    def _team_send(self, color: str | None, msg) -> None:
        self._send(self.channels.team.get(color), msg)

    def _react(self) -> None:
        """Send what the game's new events call for at once."""
        new = self.game.events[self._ev:]
        self._ev = len(self.game.events)
        changed: set[str] = set()
        for ev in new:
            if ev.kind == E.ATTENTION:
                a = self.messages.attention(ev.text, ev.team, ev.data.get("time_to_show", 10.0))
                if ev.team in TEAMS:
                    self._team_send(ev.team, a)
                self._send(self.channels.stream, a)
            elif ev.kind == E.PHASE and self.game.phase == "PRODUCTION":
                self.order_info.restart()
                self.machine_info.restart()
            elif ev.kind in (E.ORDER, E.DELIVERY):
                self.order_info.restart()
            elif ev.kind in (E.MACHINE, E.REPORT) and ev.phase == "PRODUCTION":
                changed.update([ev.team] if ev.team in TEAMS else TEAMS)
            elif ev.kind == E.ROBOT and ev.data.get("what") == "new":
                self.version.restart()
        if self.game.phase == "PRODUCTION":
            for color in sorted(changed):
                self._team_send(color, self.messages.machine_info(self.game, color))

    def _send_periodic(self, now: float) -> None:
        g, m, ch = self.game, self.messages, self.channels
        if self.beacon.due(now):
            self._send(ch.public, m.beacon(self.clock.epoch()))
        if self.gamestate.due(now):
            gs = m.game_state(g)
            self._send(ch.public, gs)
            self._send(ch.stream, gs)
        if self.version.due(now):
            self._send(ch.public, m.version_info())
        if self.robot_info_public.due(now):
            self._send(ch.public, m.robot_info(g, with_pose=False))
        streaming = ch.stream is not None and bool(ch.stream.clients())
        if streaming and self.robot_info_stream.due(now):
            self._send(ch.stream, m.robot_info(g))
        if g.exploring:
            if g.rules.sends_exploration_info and self.exploration_info.due(now):
                self._send(ch.public, m.exploration_info(g, self._rng))
            if self.report_info.due(now):
                for color in TEAMS:
                    self._team_send(color, m.machine_report_info(g, color))
        if g.phase == "PRODUCTION":
            if self.order_info.due(now):
                oi = m.order_info(g)
                self._send(ch.public, oi)
                self._send(ch.stream, oi)
            if self.machine_info.due(now):
                for color in TEAMS:
                    self._team_send(color, m.machine_info(g, color))
            if self.ring_info.due(now):
                ri = m.ring_info(g)
                for color in TEAMS:
                    self._team_send(color, ri)
        if streaming and self.machine_info_stream.due(now):
            self._send(ch.stream, m.machine_info(g, None))


class _Tapped:
    """A refbox transport that shows ``fn`` every message it sends and receives."""

    def __init__(self, inner, channel: str, fn):
        self._inner, self._channel, self._fn = inner, channel, fn

    def send(self, msg, *args, **kw):
        sent = self._inner.send(msg, *args, **kw)
        if sent:
            self._fn(self._channel, "refbox", msg)
        return sent

    def receive(self):
        got = self._inner.receive()
        for rec in got:
            self._fn(self._channel, rec.source, rec.msg)
        return got

    def __getattr__(self, name):
        return getattr(self._inner, name)
