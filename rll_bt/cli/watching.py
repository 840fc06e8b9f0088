"""``--record FILE.mcap``, ``--live [PORT]`` and ``--record-camera HZ`` of
``rll-bt agent`` and ``rll-bt teamserver``: the options and the watch they
open (:mod:`rll_bt.watch.process`), with the command line's exit codes (2 for
a recording that cannot be written, 3 for a port that cannot be served)."""
from __future__ import annotations

import sys
from pathlib import Path

from ..errors import Unavailable, UserError
from .refbox import _positive_float

LIVE_PORT = 8765


def add_options(parser, what: str, camera: bool = False) -> None:
    g = parser.add_argument_group("watching (Foxglove and rll-bt view, see README)")
    g.add_argument("--record", type=Path, metavar="FILE.mcap",
                   help=f"record {what} as MCAP (open it in Foxglove or with rll-bt view FILE)")
    g.add_argument("--live", type=int, nargs="?", const=LIVE_PORT, metavar="PORT",
                   help=f"serve the same channels over Foxglove's WebSocket protocol (default port {LIVE_PORT}; "
                        "0: any free port): Foxglove's Open connection, or rll-bt view ws://HOST:PORT")
    if camera:
        g.add_argument("--record-camera", type=_positive_float, metavar="HZ",
                       help="also take camera frames for the recording, this many a second (default: only the "
                            "frames the robot's perception reads)")


def open_watch(args, name: str, meta: dict):
    """The watch ``args`` ask for, or None."""
    if args.record is None and args.live is None:
        return None
    if args.live is not None and not 0 <= args.live < 65536:
        raise UserError(f"not a port: {args.live}", where="--live")
    from ..watch import WatchUnavailable, wall_watch
    try:
        watch = wall_watch(record=args.record, live=args.live, name=name, meta=meta)
    except WatchUnavailable as exc:
        raise Unavailable(str(exc), where="--record" if args.record is not None else "--live") from None
    except OSError as exc:
        raise UserError(f"cannot write the recording: {exc.strerror or exc}", where=f"--record {args.record}") \
            from None
    except RuntimeError as exc:          # foxglove: the port is taken
        raise Unavailable(f"cannot serve Foxglove's WebSocket: {exc}", where=f"--live {args.live}",
                          hint="another program on the port? give --live 0 for any free port") from None
    if watch.port is not None:
        print(f"{name}: Foxglove live on ws://localhost:{watch.port} (rll-bt view ws://localhost:{watch.port})",
              file=sys.stderr, flush=True)
    return watch


def close_watch(watch, args) -> None:
    if watch is None:
        return
    watch.close()
    if args.record is not None:
        n = sum(watch.counts.values())
        print(f"recorded {n} messages on {len(watch.counts)} topics to {args.record}", file=sys.stderr, flush=True)
