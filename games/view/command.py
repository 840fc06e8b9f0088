"""``rll-bt view``: the live page of a recording or of a running game.

    rll-bt view game.mcap                  # a recording (rll-bt sim|agent|teamserver --record), played back
    rll-bt view ws://localhost:8765        # a running game, agent or team server started with --live

It serves the page on ``--port`` (default 8766) until Ctrl-C (or
``--seconds``).  Exit codes: 0 served to the end of ``--seconds``, 2 a file
that is no recording or a bad option, 3 the port cannot be served or the
live server cannot be reached, 130 interrupted.
"""
from __future__ import annotations

import sys
import time
from pathlib import Path

from rll_bt.errors import Unavailable, UserError

from . import DEFAULT_PORT


def add(cli) -> None:
    p = cli.command("view", "serve the live page of a recording or of a running game (--live) in the browser")
    p.description = ("Serve a small web page showing a game: the field with the robots, their paths and the "
                     "stations, the orders and their delivery windows, the score over time and each robot's "
                     "behaviour tree with the running branch highlighted.  SOURCE is an MCAP recording "
                     "(rll-bt sim|agent|teamserver --record), played back with pause, seek and speed, or the "
                     "Foxglove WebSocket of a running game, agent or team server (--live): ws://HOST:PORT.")
    p.epilog = ("exit codes: 0 done, 2 not a recording or bad options, 3 port or live server unreachable, "
                "130 interrupted")
    p.add_argument("source", metavar="SOURCE", help="FILE.mcap, or ws://HOST:PORT of a --live Foxglove server")
    p.add_argument("--port", type=int, default=DEFAULT_PORT,
                   help=f"where the page is served (default {DEFAULT_PORT}; 0: any free port)")
    p.add_argument("--host", default="127.0.0.1", help="address to serve on (default %(default)s: this machine only)")
    p.add_argument("--speed", type=float, default=1.0, metavar="X",
                   help="a recording's playback speed, game seconds per wall second (default 1)")
    p.add_argument("--paused", action="store_true", help="a recording starts paused (press play on the page)")
    p.add_argument("--profile", metavar="NAME",
                   help="rules profile whose field is drawn (default: the recording's, or the one a live server's "
                        "name tells, else rcll2016)")
    p.add_argument("--seconds", type=float, metavar="S", help="stop after S seconds (default: serve until Ctrl-C)")
    p.set_defaults(func=run)


def _is_live(source: str) -> bool:
    return source.startswith(("ws://", "wss://"))


def run(args) -> int:
    from rll_bt import rules

    from .server import ViewServer
    if not 0 <= args.port < 65536:
        raise UserError(f"not a port: {args.port}", where="--port")
    if not 0 < args.speed <= 1000:
        raise UserError(f"must be in (0, 1000], not {args.speed}", where="--speed")
    if args.profile is not None and args.profile not in rules.PROFILES:
        raise UserError(f"unknown profile {args.profile!r}", where="--profile",
                        hint=f"one of {', '.join(rules.PROFILES)}")
    state, control, owner, what = _open_live(args) if _is_live(args.source) else _open_recording(args)
    try:
        server = ViewServer(state, port=args.port, host=args.host, control=control)
    except OSError as exc:
        owner.close()
        raise Unavailable(f"cannot serve the page: {exc.strerror or exc}", where=f"--port {args.port}",
                          hint="another program on the port? give --port 0 for any free port") from None
    print(f"rll-bt view: {what}; open {server.url} in a browser (Ctrl-C stops)", file=sys.stderr, flush=True)
    start = time.monotonic()
    try:
        while args.seconds is None or time.monotonic() - start < args.seconds:
            time.sleep(0.2)
            if getattr(owner, "error", None):
                print(f"rll-bt view: {owner.error}", file=sys.stderr)
                return 3
    except KeyboardInterrupt:
        return 130
    finally:
        server.close()
        owner.close()
    return 0


def _open_recording(args):
    from .sources import Playback, SourceError, read_recording
    from .state import ViewState
    path = Path(args.source)
    if not path.is_file():
        raise UserError("file not found", where=str(path), hint="give a recording (FILE.mcap) or ws://HOST:PORT")
    try:
        meta, messages = read_recording(path)
    except SourceError as exc:
        raise UserError(str(exc), where=str(path), hint="give a recording made with --record") from None
    profile = args.profile or meta.get("profile") or "rcll2016"
    team = meta.get("team", "CYAN")
    state = ViewState(profile, meta={"source": "replay", "file": path.name, "kind": meta.get("kind", "?"),
                                     "name": meta.get("name", "rll-bt")}, team=team)
    playback = Playback(state, messages, speed=args.speed, playing=not args.paused)
    playback.start()
    return state, playback.control, playback, f"{path} ({len(messages)} messages shown, " \
                                    f"{playback.end_t - playback.start_t:.0f} s)"


def _open_live(args):
    from .sources import FoxgloveSource
    from .state import ViewState
    state = ViewState(args.profile or "rcll2016", meta={"source": "foxglove", "url": args.source})
    src = FoxgloveSource(state, args.source)
    src.start()
    src.connected.wait(10.0)
    if src.error or src.server_name is None:
        src.close()
        raise Unavailable(src.error or "no answer", where=args.source,
                          hint="is a game, agent or team server running with --live on that port?")
    if args.profile:
        state.set_meta(profile=args.profile)
    return state, None, src, f"following {src.server_name!r} at {args.source}"
