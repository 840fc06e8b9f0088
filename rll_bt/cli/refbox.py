"""``rll-bt refbox monitor|send``: listen to and talk on the refbox's channels like a robot.

``monitor`` joins the public channel and, once the team colour is known
(``--color``, or learnt from a GameState naming ``--team`` as team_cyan or
team_magenta), the team's encrypted channel; it prints every decoded message
as one JSON line ``{"type": ..., "channel": "public"|"team", "msg": {...}}``
and summarises dropped frames on stderr when it ends.

``send`` encodes one message from JSON (protobuf's JSON mapping, original
field names, enums by name) and sends it on the team channel (encrypted with
the team key) or, with ``--public``, on the public channel.

Ports are given from the robot's side: ``--X-recv`` is where this tool
listens, ``--X-send`` where it sends.  They default to ``--layout``
(competition: one port per channel; sim: the refbox's split local ports).
"""
from __future__ import annotations

import json
import sys

from ..clock import WallClock
from ..errors import Unavailable, UserError

TEAM_CHANNEL = "team"


def register(cli) -> None:
    sub = cli.group("refbox")
    mon = sub.add_parser(
        "monitor", help="print every refbox message on the public and team channels as JSON lines",
        description="Join the public channel and the team's encrypted channel like a robot "
                    "and print each decoded message as one JSON object per line: "
                    '{"type": ..., "channel": "public"|"team", "msg": {...}}. Undecodable '
                    "frames are counted and summarised on stderr at exit.")
    _common_args(mon, key_required=True)
    mon.add_argument("--count", type=_positive_int, metavar="N",
                     help="exit after N messages (exit 1 if --seconds ends first)")
    mon.add_argument("--seconds", type=_positive_float, metavar="S",
                     help="exit after S seconds (exit 3 if nothing at all arrived)")
    mon.set_defaults(func=cmd_monitor)

    snd = sub.add_parser(
        "send", help="encode and send one message from JSON on the team (or public) channel",
        description="Encode one message given as JSON (protobuf's JSON mapping with the "
                    "original field names, enums by name) and send it on the team's encrypted "
                    "channel, or on the public channel with --public.")
    _common_args(snd, key_required=False)
    snd.add_argument("--type", required=True, metavar="T",
                     help="message type, e.g. BeaconSignal, MachineReport, PrepareMachine")
    snd.add_argument("--json", default="{}", metavar="JSON",
                     help="the message as a JSON object (default: {})")
    snd.add_argument("--public", action="store_true",
                     help="send on the public channel instead of the team channel")
    snd.add_argument("--wait", type=_positive_float, default=5.0, metavar="S",
                     help="without --color: seconds to wait for a GameState naming the team "
                          "(default 5)")
    snd.set_defaults(func=cmd_send)


def _number(kind: type, what: str, lo: float, hi: float | None = None):
    """An argparse type: a ``kind`` number > ``lo`` (and < ``hi``)."""
    def parse(text: str):
        import argparse
        try:
            v = kind(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"not {what}: {text!r}") from None
        if not (v > lo and (hi is None or v < hi)):
            bounds = f"between {lo} and {hi}" if hi is not None else f"greater than {lo}"
            raise argparse.ArgumentTypeError(f"must be {bounds}, not {text}")
        return v
    return parse


_positive_int = _number(int, "an integer", 0)
_positive_float = _number(float, "a number", 0.0)
_port = _number(int, "a port number", 0, 65536)


def _common_args(p, key_required: bool) -> None:
    from ..comm import DEFAULT_HOST, LAYOUTS
    p.add_argument("--profile", default="rcll2016",
                   help="rules profile / refbox message set: rcll2016 (default) or rcll2025")
    p.add_argument("--team", required=True, metavar="NAME",
                   help="team name exactly as configured in the refbox")
    p.add_argument("--key", required=key_required, metavar="KEY",
                   help="the team's crypto key (refbox llsfrb/game/crypto-keys/<team>)")
    p.add_argument("--color", choices=("cyan", "magenta"),
                   help="team colour (default: learnt from GameState on the public channel)")
    p.add_argument("--host", default=DEFAULT_HOST,
                   help=f"address to send to, e.g. a broadcast address (default {DEFAULT_HOST})")
    p.add_argument("--layout", choices=sorted(LAYOUTS), default="competition",
                   help="default ports: competition (4444/4441/4442 send+listen) or sim "
                        "(the refbox's split local ports)")
    for chan in ("public", "team"):
        p.add_argument(f"--{chan}-recv", type=_port, metavar="N",
                       help=f"port to listen on for the {chan} channel")
        p.add_argument(f"--{chan}-send", type=_port, metavar="N",
                       help=f"port to send to on the {chan} channel")


# -- helpers -------------------------------------------------------------------------------

def _message_set(profile: str):
    from .. import msgs
    if profile not in msgs.PROFILES:
        raise UserError(f"unknown profile {profile!r}", where="--profile",
                        hint=f"one of {', '.join(msgs.PROFILES)}")
    return msgs.message_set(profile)


def _ports(args, channel: str, color: str | None):
    """(send, recv) ports for "public" or "team" from the layout and the explicit options."""
    from ..comm import layout
    lay = layout(args.layout)
    if channel == "public":
        base = lay.robot("public")
    else:
        base = lay.robot(color) if color else None
    send = getattr(args, f"{channel}_send") or (base.send if base else None)
    recv = getattr(args, f"{channel}_recv") or (base.recv if base else None)
    return send, recv


def _open_peer(args, registry, channel: str, send: int, recv: int | None, key=None):
    from ..comm import UdpPeer
    try:
        return UdpPeer(args.host, send, recv, registry=registry, channel=channel, key=key)
    except OSError as exc:
        where = f"{channel} channel, port {recv if recv is not None else send}"
        if isinstance(exc, PermissionError):
            raise UserError(f"cannot bind: {exc}", where=where) from None
        raise Unavailable(f"cannot open the UDP socket: {exc}", where=where,
                          hint="is --host a valid address and the port free?") from None


def _color_from_gamestate(msg, team: str) -> str | None:
    if msg.DESCRIPTOR.name != "GameState":
        return None
    if getattr(msg, "team_cyan", "") == team:
        return "cyan"
    if getattr(msg, "team_magenta", "") == team:
        return "magenta"
    return None


def _say(text: str) -> None:
    print(f"rll-bt refbox: {text}", file=sys.stderr, flush=True)


# -- monitor -------------------------------------------------------------------------------

class _Monitor:
    """The monitor's channels: public always, the team channel once the colour is known."""

    def __init__(self, args, registry):
        self.args, self.registry = args, registry
        send, recv = _ports(args, "public", None)
        self.public = _open_peer(args, registry, "public", send, recv)
        _say(f"public channel: listening on :{self.public.recv_port}, profile {args.profile}")
        self.team = None
        self.color = None
        self.closed_stats: list[str] = []
        if args.color:
            self.join_team(args.color)

    def join_team(self, color: str) -> None:
        if self.team is not None:
            self.closed_stats.append(self.team.stats.summary())
            self.team.close()
        send, recv = _ports(self.args, "team", color)
        self.team = _open_peer(self.args, self.registry, TEAM_CHANNEL, send, recv, key=self.args.key)
        self.color = color
        _say(f"team channel ({color}, encrypted): listening on :{self.team.recv_port}, "
             f"sending to {self.args.host}:{send}")

    def peers(self):
        return [p for p in (self.public, self.team) if p is not None]

    def close(self) -> None:
        for p in self.peers():
            p.close()

    def summary(self) -> list[str]:
        lines = list(self.closed_stats)
        for p in self.peers():
            s = p.stats
            lines.append(s.summary() + (f"; {s.own} own datagrams ignored" if s.own else ""))
        return lines


def cmd_monitor(args) -> int:
    from .. import msgs
    from ..comm import MessageRegistry
    ms = _message_set(args.profile)
    registry = MessageRegistry.from_message_set(ms)
    clock = WallClock()
    mon = _Monitor(args, registry)
    start = clock.now()
    printed = 0
    try:
        while True:
            if args.count and printed >= args.count:
                return 0
            if args.seconds is not None and clock.now() - start >= args.seconds:
                break
            peers = mon.peers()
            for p in peers:
                p.wait(0.05 / len(peers))
            for p in peers:
                for rec in p.receive():
                    if args.count and printed >= args.count:
                        break
                    line = {"type": rec.type_name, "channel": rec.channel,
                            "msg": msgs.to_dict(rec.msg)}
                    print(json.dumps(line, separators=(",", ":")), flush=True)
                    printed += 1
                    color = _color_from_gamestate(rec.msg, args.team) if not args.color else None
                    if color and color != mon.color:
                        mon.join_team(color)
        if args.count:
            _say(f"received {printed} of {args.count} messages in {args.seconds:g} s")
            return 3 if printed == 0 else 1
        if printed == 0:
            _say(f"no refbox message in {args.seconds:g} s (host {args.host}, "
                 f"layout {args.layout})")
            return 3
        return 0
    finally:
        mon.close()
        for line in mon.summary():
            _say(line)


# -- send ----------------------------------------------------------------------------------

def _build_message(ms, type_name: str, text: str):
    from .. import msgs
    from ..comm import comp_type_of
    cls = ms.all_classes.get(type_name) if hasattr(ms, "all_classes") else ms.classes.get(type_name)
    if cls is None:
        raise UserError(f"unknown message type {type_name!r} in {ms.name}", where="--type",
                        hint="one of " + ", ".join(sorted(ms.classes)))
    if comp_type_of(cls) is None:
        raise UserError(f"{type_name} has no CompType, so it is only sent inside another message",
                        where="--type", hint="one of " + ", ".join(sorted(ms.classes)))
    try:
        data = json.loads(text)
    except json.JSONDecodeError as exc:
        raise UserError(f"bad JSON: {exc.msg} at line {exc.lineno} column {exc.colno}",
                        where="--json") from None
    if not isinstance(data, dict):
        raise UserError(f"expected a JSON object, got {type(data).__name__}", where="--json")
    try:
        msg = msgs.from_dict(ms, type_name, data)
    except (ValueError, KeyError, TypeError) as exc:
        raise UserError(str(exc).strip(), where="--json") from None
    missing = msg.FindInitializationErrors()
    if missing:
        raise UserError(f"{type_name} lacks required field(s): {', '.join(missing)}",
                        where="--json")
    return msg


def _learn_color(args, registry, clock) -> str:
    send, recv = _ports(args, "public", None)
    public = _open_peer(args, registry, "public", send, recv)
    _say(f"waiting up to {args.wait:g} s for a GameState naming {args.team!r} "
         f"on :{public.recv_port}")
    try:
        end = clock.now() + args.wait
        while clock.now() < end:
            public.wait(0.05)
            for rec in public.receive():
                color = _color_from_gamestate(rec.msg, args.team)
                if color:
                    return color
    finally:
        public.close()
    raise Unavailable(f"no GameState naming team {args.team!r} within {args.wait:g} s",
                      where=f"public channel :{recv}",
                      hint="is the refbox running with this team set? or give --color")


def cmd_send(args) -> int:
    from ..comm import FrameTooLarge, MessageRegistry
    if not args.public and not args.key:
        raise UserError("the team channel is encrypted: give the team key", where="--key",
                        hint="or send on the public channel with --public")
    ms = _message_set(args.profile)
    msg = _build_message(ms, args.type, args.json)
    registry = MessageRegistry.from_message_set(ms)
    if args.public:
        channel, key, color = "public", None, None
    else:
        channel, key = TEAM_CHANNEL, args.key
        color = args.color or (None if args.team_send else _learn_color(args, registry,
                                                                          WallClock()))
    send, _recv = _ports(args, channel, color)
    # bind an ephemeral port unless one is given: do not take datagrams meant for a
    # monitor or agent listening on this host
    recv = getattr(args, f"{channel}_recv") or 0
    peer = _open_peer(args, registry, channel, send, recv, key=key)
    try:
        try:
            frame = peer.codec.encode(msg)
        except FrameTooLarge as exc:
            raise UserError(str(exc), where="--json") from None
        ok = peer.send_frame(frame)
    finally:
        peer.close()
    if not ok:
        raise Unavailable(f"the OS refused to send to {args.host}:{send}", where="--host")
    how = f"encrypted, {color or 'team'}" if key else "plain"
    _say(f"sent {args.type} ({len(frame)} bytes, {how}) to {args.host}:{send} on the "
         f"{channel} channel")
    return 0
