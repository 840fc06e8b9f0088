"""``rll-bt refbox sim``: the simulated refbox as a standalone process on UDP.

It plays the 2016 rules (``--profile rcll2016``, the default) or today's
(``--profile rcll2025``: no EXPLORATION phase, reports by zone and rotation
in the first 180 s of PRODUCTION) with its own headless PyBullet world (or the
in-memory table world), speaks the real wire protocol on the public, cyan and
magenta channels and its plain TCP control stream, prints one line per phase
change with the score, and ends cleanly on SIGINT/SIGTERM (or after the game
with ``--quit-after-game``).  Its world has no robots, so by default
(``--mockup auto``) stations run in mockup mode (:mod:`.mockup`): virtual
robots take products off outputs and feed prepared stations, and a team
playing by PrepareMachine alone can produce and deliver.  Exit codes: 0 ok, 2 bad arguments, 3 a port or
PyBullet could not be opened.
"""
from __future__ import annotations

import signal
import sys

from rll_bt.errors import Unavailable, UserError

LOOP_PERIOD = 0.02        # wall seconds between two steps of the refbox


def register(cli) -> None:
    sub = cli.group("refbox")
    p = sub.add_parser(
        "sim", help="run a simulated refbox (2016 or 2025 rules) on UDP that any team can play "
                    "against",
        description="Run the simulated referee box as a standalone process: random mirrored "
                    "field, exploration (2016: light codes; 2025: zone and rotation reports in "
                    "the first minutes of production), orders, stations, scoring, on the real "
                    "wire protocol (public channel plain, team channels AES-128-CBC with each "
                    "team's key, TCP control stream plain). Prints a line per phase change "
                    "with the score; stop it with Ctrl-C.",
        epilog="exit codes: 0 ok, 2 bad arguments, 3 a port or PyBullet could not be opened")
    p.add_argument("--profile", default="rcll2016",
                   help="rules profile: rcll2016 (default) or rcll2025")
    p.add_argument("--team-cyan", required=True, metavar="NAME", help="team playing cyan")
    p.add_argument("--key-cyan", metavar="KEY",
                   help="crypto key of the cyan team (or give it as --key KEY)")
    p.add_argument("--team-magenta", metavar="NAME", help="team playing magenta (optional)")
    p.add_argument("--key-magenta", metavar="KEY", help="crypto key of the magenta team")
    p.add_argument("--key", action="append", default=[], metavar="KEY|NAME=KEY",
                   help="KEY alone: the cyan team's key (as --key-cyan); NAME=KEY: the key of a "
                        "team that may be named later by SetTeamName (repeatable)")
    p.add_argument("--seed", type=int, default=0, metavar="N",
                   help="fixes field, light codes, orders, ring costs, down times (default 0)")
    p.add_argument("--host", default="127.0.0.1",
                   help="address to send to, e.g. a broadcast address (default 127.0.0.1)")
    p.add_argument("--ports", choices=("competition", "sim"), default="sim",
                   help="UDP layout: sim = the refbox's split local ports (send 4444/4441/4442, "
                        "listen 4445/4446/4447; default), competition = one port per channel")
    p.add_argument("--port-offset", type=int, default=0, metavar="N",
                   help="add N to every UDP and TCP port (several refboxes on one host)")
    p.add_argument("--no-stream", action="store_true", help="do not open the TCP control stream")
    p.add_argument("--start", choices=("now", "command"), default="now",
                   help="now: start the game at once (default); command: wait for "
                        "SetGameState RUNNING (and SetTeamName) on the TCP stream or the public "
                        "channel")
    p.add_argument("--speed", type=float, default=1.0, metavar="X",
                   help="game seconds per wall second (default 1)")
    p.add_argument("--phase-lengths", default="", metavar="SPEC",
                   help="e.g. setup=10,exploration=60,production=300,overtime=60 (seconds); "
                        "with rcll2025, exploration is the reporting time inside production")
    p.add_argument("--world", choices=("bullet", "table"), default="bullet",
                   help="bullet: a headless PyBullet world (default); table: in memory only")
    p.add_argument("--mockup", choices=("auto", "on", "off"), default="auto",
                   help="mockup stations: a prepared station is fed the team's product by a "
                        "virtual robot and its output emptied after a while, so production "
                        "works without robots; auto (default): on when the world has no robots "
                        "(always so here)")
    p.add_argument("--quit-after-game", action="store_true",
                   help="exit once the game reaches POST_GAME")
    p.set_defaults(func=cmd_sim)


def _settings(args):
    """Validated (profile, timing, keys) from the arguments; UserError otherwise."""
    from rll_bt import rules
    from .ruleset import rules_for
    from .timing import Timing, parse_phase_lengths
    try:
        prof = rules.profile(args.profile)
        rules_for(prof)
    except ValueError as exc:
        raise UserError(str(exc), where="--profile") from None
    if bool(args.team_magenta) != bool(args.key_magenta):
        raise UserError("give --team-magenta and --key-magenta together", where="--team-magenta")
    if args.team_magenta and args.team_magenta == args.team_cyan:
        raise UserError(f"both teams are called {args.team_cyan!r}", where="--team-magenta")
    if not (args.speed > 0 and args.speed < 1e6):
        raise UserError(f"must be a positive number, not {args.speed}", where="--speed")
    if not 0 <= args.port_offset <= 60000:
        raise UserError(f"must be 0..60000, not {args.port_offset}", where="--port-offset")
    try:
        timing = Timing.from_profile(prof, speed=args.speed,
                                     **parse_phase_lengths(args.phase_lengths))
    except ValueError as exc:
        raise UserError(str(exc), where="--phase-lengths") from None
    keys, cyan_key = {}, args.key_cyan
    for item in args.key:
        name, sep, key = item.partition("=")
        if not sep:
            if cyan_key is not None and cyan_key != item:
                raise UserError("the cyan team's key is given twice (--key-cyan, or --key without NAME=)",
                                where="--key")
            cyan_key = item
        elif not name or not key:
            raise UserError(f"expected KEY or NAME=KEY, not {item!r}", where="--key")
        else:
            keys[name] = key
    if not cyan_key:
        raise UserError(f"no key for the cyan team {args.team_cyan!r}: give --key KEY or --key-cyan KEY",
                        where="--key")
    keys[args.team_cyan] = cyan_key
    if args.team_magenta:
        keys[args.team_magenta] = args.key_magenta
    return prof, timing, keys


def _layout(args):
    from rll_bt.comm import COMPETITION, SIM, Layout, PeerPorts
    base = COMPETITION if args.ports == "competition" else SIM
    o = args.port_offset

    def shift(pp):
        return PeerPorts(pp.send + o, pp.recv + o)
    return Layout(f"{base.name}+{o}" if o else base.name, shift(base.public), shift(base.cyan),
                  shift(base.magenta), base.stream + o)


def mockup_wanted(choice: str, world) -> bool:
    """``--mockup``: "on", "off", or "auto" = on when ``world`` has no robots."""
    if choice == "auto":
        return not getattr(world, "robots", None)
    return choice == "on"


def _score(game) -> str:
    c, m = game.teams["CYAN"] or "-", game.teams["MAGENTA"] or "-"
    return f"{c} {game.points('CYAN')} : {game.points('MAGENTA')} {m}"


def cmd_sim(args) -> int:
    from rll_bt.clock import WallClock
    from .game import RefboxGame
    from .node import RefboxNode
    from .stations import StationConfig
    from .world import TableWorld

    prof, timing, keys = _settings(args)
    lay = _layout(args)
    clock = WallClock()
    world = None
    try:
        if args.world == "bullet":
            from backends.sim.world import World
            world = World(prof, seed=args.seed)
        else:
            world = TableWorld.generated(prof, args.seed)
    except Exception as exc:  # noqa: BLE001 - PyBullet missing or failing
        raise Unavailable(f"cannot build the PyBullet world: {exc}",
                          hint="use --world table to run without PyBullet") from None
    game = RefboxGame(prof, clock, world, seed=args.seed, team_cyan=args.team_cyan,
                      team_magenta=args.team_magenta, timing=timing, config=StationConfig(),
                      mockup=mockup_wanted(args.mockup, world))
    try:
        node = RefboxNode.on_udp(game, host=args.host, layout=lay, keys=keys,
                                 stream_port=-1 if args.no_stream else lay.stream,
                                 control_via_public=args.start == "command")
    except OSError as exc:
        _close(world)
        raise Unavailable(f"cannot open the refbox ports ({lay.name} layout, host {args.host}): "
                          f"{exc}", hint="another refbox running? try --port-offset") from None

    stop = []

    def on_signal(signum, _frame):
        stop.append(signum)
    old = {s: signal.signal(s, on_signal) for s in (signal.SIGINT, signal.SIGTERM)}
    out = sys.stdout
    pp = lambda c: f"{lay.refbox(c).send}/{lay.refbox(c).recv}"  # noqa: E731
    print(f"refbox sim: {prof.name}, seed {args.seed}, cyan {args.team_cyan}"
          + (f", magenta {args.team_magenta}" if args.team_magenta else "")
          + f"; UDP to {args.host} send/listen public {pp('public')}, cyan {pp('cyan')}, "
            f"magenta {pp('magenta')}"
          + ("" if args.no_stream else f"; TCP stream {lay.stream}")
          + f"; mockup stations {'on' if game.mockup else 'off'}", file=out, flush=True)
    if args.start == "now":
        game.start()
    else:
        print("waiting for SetGameState RUNNING (TCP stream or public channel)", file=out,
              flush=True)
    seen = 0
    start = last_wall = clock.now()
    try:
        while not stop:
            node.step()
            now = clock.now()
            if hasattr(world, "step"):
                world.step(min(max(now - last_wall, 0.0), 0.5))
            last_wall = now
            for ev in game.events[seen:]:
                if ev.kind == "phase" and not ev.data.get("final"):
                    print(f"[{clock.now() - start:7.1f} s] {ev.text.replace('phase ', '')}"
                          f"{' (overtime)' if ev.data.get('overtime') else ''}  {_score(game)}",
                          file=out, flush=True)
                elif ev.kind == "report" and ev.data.get("what") == "ground-truth":
                    print(f"[{clock.now() - start:7.1f} s] {ev.text}  {_score(game)}", file=out,
                          flush=True)
            seen = len(game.events)
            if args.quit_after_game and game.phase == "POST_GAME":
                break
            node.channels.public.wait(LOOP_PERIOD)
    finally:
        for s, h in old.items():
            signal.signal(s, h)
        node.close()
        _close(world)
    print(f"final score: {_score(game)} ({game.phase}"
          + (f", stopped by signal {stop[0]}" if stop else "") + ")", file=out, flush=True)
    return 0


def _close(world) -> None:
    close = getattr(world, "close", None)
    if close is not None:
        close()
