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
PyBullet could not be opened, or the remote world was lost.

With ``--world remote:HOST:PORT`` the refbox has no world of its own: it
drives the stations of a world served over the station link
(:mod:`.link`), as ``rll-bt sim --processes`` runs it, and takes the
world's operator commands (start, a station DOWN) from that link.  If the
world closes the link (its process ended) or stops answering, the refbox
says so in one line and exits 3.  Its clock is the world's: it stands
while the world's time, pushed over the link, stands (a world fallen
behind the wall clock), so a game's seconds are the world's.  ``--snapshot FILE`` rewrites FILE with
the game as plain JSON (:mod:`.view`) every ``--snapshot-period`` s and at
exit; ``--message-log FILE`` writes every message sent and received as
JSON lines on the monotonic clock (the schema of ``rll-bt sim``'s
``messages.jsonl``; ``from`` is "refbox", a beacon's peer name, or the
sender's HOST:PORT).
"""
from __future__ import annotations

import signal
import sys
from pathlib import Path

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
        epilog="exit codes: 0 ok, 2 bad arguments, 3 a port or PyBullet could not be opened, or the "
               "remote world was lost")
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
    p.add_argument("--ports", default="sim", metavar="LAYOUT",
                   help="UDP layout: sim = the refbox's split local ports (send 4444/4441/4442, "
                        "listen 4445/4446/4447; default), competition = one port per channel, or "
                        "public=SEND/LISTEN,cyan=SEND/LISTEN,magenta=SEND/LISTEN")
    p.add_argument("--port-offset", type=int, default=0, metavar="N",
                   help="add N to every UDP and TCP port (several refboxes on one host)")
    p.add_argument("--no-stream", action="store_true", help="do not open the TCP control stream")
    p.add_argument("--start", choices=("now", "command"), default="now",
                   help="now: start the game at once (default); command: wait for "
                        "SetGameState RUNNING (and SetTeamName) on the TCP stream or the public "
                        "channel, or with --world remote the world's start on the station link")
    p.add_argument("--speed", type=float, default=1.0, metavar="X",
                   help="game seconds per wall second (default 1)")
    p.add_argument("--phase-lengths", default="", metavar="SPEC",
                   help="e.g. setup=10,exploration=60,production=300,overtime=60 (seconds); "
                        "with rcll2025, exploration is the reporting time inside production")
    p.add_argument("--world", type=_world_choice, default="bullet", metavar="WORLD",
                   help="bullet: a headless PyBullet world (default); table: in memory only; "
                        "remote:HOST:PORT: the stations of a world in another process, over the "
                        "station link (rll-bt sim --processes); mqtt:HOST:PORT: the stations are "
                        "machines on the refbox's MQTT topics behind this broker, driven as the "
                        "real refbox drives them (rll-bt sim --refbox external serves them)")
    p.add_argument("--time-sync", action="store_true",
                   help="the game's clock follows the SimTimeSync a simulation sends on the TCP stream "
                        "(the real refbox's llsfrb/simulation/time-sync): paused while it is paused, "
                        "at its speed in between")
    p.add_argument("--mockup", choices=("auto", "on", "off"), default="auto",
                   help="mockup stations: a prepared station is fed the team's product by a "
                        "virtual robot and its output emptied after a while, so production "
                        "works without robots; auto (default): on when the world has no robots "
                        "(its own world never has; a remote one says)")
    p.add_argument("--game", metavar="FILE",
                   help="play a stored game: its field, orders, ring colours and costs and down periods "
                        "(rll-bt JSON from --save-game, or the first game of a refbox archive of game "
                        "reports); a remote world must stand on its field")
    p.add_argument("--save-game", metavar="FILE",
                   help="write the game's field, orders, ring setup and down periods to FILE (JSON) "
                        "at the start, for --game")
    p.add_argument("--quit-after-game", action="store_true",
                   help="exit once the game reaches POST_GAME")
    p.add_argument("--snapshot", metavar="FILE",
                   help="rewrite FILE with the game as JSON (status, points, awards, deliveries, "
                        "station states, orders) every --snapshot-period s and at exit")
    p.add_argument("--snapshot-period", type=float, default=1.0, metavar="S",
                   help="seconds between two snapshots (default 1)")
    p.add_argument("--message-log", metavar="FILE",
                   help="write every message sent and received to FILE as JSON lines")
    p.set_defaults(func=cmd_sim)


def _world_choice(text: str) -> str:
    import argparse
    if text in ("bullet", "table") or text.startswith(("remote:", "mqtt:")):
        return text
    raise argparse.ArgumentTypeError(f"expected bullet, table, remote:HOST:PORT or mqtt:HOST:PORT, not {text!r}")


def _settings(args):
    """Validated (profile, timing, keys) from the arguments; UserError otherwise."""
    from rll_bt import rules

    from .rulesets import rules_for
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
    if args.ports not in ("competition", "sim"):
        return _explicit_layout(args.ports, SIM.stream + args.port_offset)
    base = COMPETITION if args.ports == "competition" else SIM
    o = args.port_offset

    def shift(pp):
        return PeerPorts(pp.send + o, pp.recv + o)
    return Layout(f"{base.name}+{o}" if o else base.name, shift(base.public), shift(base.cyan),
                  shift(base.magenta), base.stream + o)


def _explicit_layout(spec: str, stream: int):
    """``public=S/L,cyan=S/L,magenta=S/L`` (the refbox's send and listen ports) as a Layout."""
    from rll_bt.comm import Layout, PeerPorts
    ports = {}
    for item in spec.split(","):
        name, _, pair = item.partition("=")
        send, _, listen = pair.partition("/")
        try:
            pp = PeerPorts(int(send), int(listen))
        except ValueError:
            pp = None
        if name not in ("public", "cyan", "magenta") or pp is None or \
                not all(0 < p < 65536 for p in (pp.send, pp.recv)):
            raise UserError(f"expected sim, competition or public=SEND/LISTEN,cyan=SEND/LISTEN,"
                            f"magenta=SEND/LISTEN, not {spec!r}", where="--ports")
        ports[name] = pp
    if len(ports) != 3:
        raise UserError(f"give the ports of public, cyan and magenta, not {spec!r}", where="--ports")
    return Layout("explicit", ports["public"], ports["cyan"], ports["magenta"], stream)


def mockup_wanted(choice: str, world) -> bool:
    """``--mockup``: "on", "off", or "auto" = on when ``world`` has no robots."""
    if choice == "auto":
        return not getattr(world, "robots", None)
    return choice == "on"


def _score(game) -> str:
    c, m = game.teams["CYAN"] or "-", game.teams["MAGENTA"] or "-"
    return f"{c} {game.points('CYAN')} : {game.points('MAGENTA')} {m}"


def _stored(args, prof):
    """The stored game of ``--game`` (None without), checked against the profile."""
    if not args.game:
        return None
    from ..stored import StoredGameError, load_game
    try:
        stored = load_game(args.game)
    except StoredGameError as exc:
        raise UserError(str(exc), where="--game") from None
    if stored.profile != prof.name:
        raise UserError(f"the stored game is {stored.profile}, not {prof.name}", where="--game",
                        hint=f"add --profile {stored.profile}")
    return stored


def _open_world(args, prof, stored=None):
    """The refbox's world: PyBullet, a table, or a remote world's stations
    (on the field of ``stored`` when given)."""
    from .world import TableWorld, WorldLost
    layout = stored.layout(args.seed) if stored is not None else None
    if args.world == "table":
        return TableWorld(layout) if layout is not None else TableWorld.generated(prof, args.seed)
    if args.world.startswith("mqtt:"):
        from rll_bt.comm.jsonlink import parse_address

        from .machines import MachineWorld
        try:
            host, port = parse_address(args.world[len("mqtt:"):], "the broker's address")
        except ValueError as exc:
            raise UserError(str(exc), where="--world") from None
        if layout is None:
            layout = TableWorld.generated(prof, args.seed).layout
        try:
            return MachineWorld(layout, host, port)
        except ConnectionError as exc:
            raise Unavailable(str(exc), where="--world",
                              hint="start the broker first (e.g. rll-bt sim stations --broker amqtt)") from None
    if args.world.startswith("remote:"):
        from .link import RemoteWorld
        try:
            world = RemoteWorld(args.world[len("remote:"):])
        except WorldLost as exc:
            raise Unavailable(str(exc), where="--world") from None
        if world.layout.profile != prof.name:
            world.close()
            raise UserError(f"the world plays {world.layout.profile}, not {prof.name}", where="--world")
        return world
    try:
        from backends.sim.world import World
        return World(prof, seed=args.seed, layout=layout)
    except Exception as exc:
        raise Unavailable(f"cannot build the PyBullet world: {exc}",
                          hint="use --world table to run without PyBullet") from None


def _message_log(path, game):
    """A tap writing the node's messages to ``path`` (JSON lines, the game's clock)."""
    from rll_bt.comm.msglog import MessageLog

    from .node import RefboxNode
    log = MessageLog(path, game.clock, {}, RefboxNode.registry(game), line_buffered=True)

    def record(channel, source, msg):
        if source != "refbox":
            if msg.DESCRIPTOR.name == "BeaconSignal" and msg.peer_name:
                source = msg.peer_name
            elif isinstance(source, tuple):
                source = f"{source[0]}:{source[1]}"
        log.record(channel, source, msg)
    return log, record


def cmd_sim(args) -> int:
    from rll_bt.clock import SyncedClock, WallClock

    from .game import RefboxGame
    from .node import RefboxNode
    from .stations import StationConfig
    from .world import WorldLost

    prof, timing, keys = _settings(args)
    lay = _layout(args)
    if not args.snapshot_period > 0:
        raise UserError(f"must be a positive number, not {args.snapshot_period}", where="--snapshot-period")
    remote = args.world.startswith("remote:")
    # a remote world's time (pushed over the station link) runs the game's clock, as SimTimeSync does
    clock = SyncedClock(WallClock()) if args.time_sync or remote else WallClock()
    stored = _stored(args, prof)
    world = _open_world(args, prof, stored)
    if remote and not args.time_sync:
        world.on_time(lambda t: clock.sync(t, rate=0.0))
    machines = args.world.startswith("mqtt:")
    try:
        config = StationConfig()
        if machines:
            from .machines import machine_config
            config = machine_config(base=config)
        game = RefboxGame(prof, clock, world, seed=args.seed, team_cyan=args.team_cyan,
                          team_magenta=args.team_magenta, timing=timing, config=config,
                          mockup=args.mockup == "on" if machines else mockup_wanted(args.mockup, world))
        _stored_game(game, stored, args)
        if machines:
            world.attach(game)
    except WorldLost as exc:
        _close(world)
        raise Unavailable(str(exc), where="--world") from None
    except UserError:
        _close(world)
        raise
    try:
        node = RefboxNode.on_udp(game, host=args.host, layout=lay, keys=keys,
                                 stream_port=-1 if args.no_stream else lay.stream,
                                 control_via_public=args.start == "command")
    except OSError as exc:
        _close(world)
        raise Unavailable(f"cannot open the refbox ports ({lay.name} layout, host {args.host}): "
                          f"{exc}", hint="another refbox running? try --port-offset") from None
    msglog = None
    if args.message_log:
        msglog, record = _message_log(args.message_log, game)
        node.tap(record)
    view = None
    if args.snapshot:
        import os

        from .view import GameView, snapshot, write_snapshot
        view, pid = GameView(game), os.getpid()

        def write() -> None:
            write_snapshot(Path(args.snapshot), {**snapshot(view), "pid": pid, "now": clock.now()})
    if remote:
        def on_command(cmd: dict) -> None:
            try:
                if cmd.get("op") == "start":
                    if game.phase == "PRE_GAME":
                        game.start()
                elif cmd.get("op") == "down":
                    game.station_down(cmd["machine"], float(cmd["seconds"]))
                else:
                    print(f"unknown command from the world: {cmd}", file=sys.stderr, flush=True)
            except (KeyError, ValueError, RuntimeError) as exc:
                print(f"command {cmd} refused: {exc}", file=sys.stderr, flush=True)
        world.on_command(on_command)

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
          + (f"; stations of the world at {world.address} (station link)" if remote else "")
          + (f"; stations are MQTT machines behind the broker at {world.address}" if machines else "")
          + ("; the clock follows SimTimeSync" if args.time_sync else "")
          + f"; mockup stations {'on' if game.mockup else 'off'}", file=out, flush=True)
    if args.start == "now":
        game.start()
    else:
        print("waiting for SetGameState RUNNING (TCP stream or public channel"
              + (", or the world's start" if remote else "") + ")", file=out, flush=True)
    seen = 0
    lost = None
    start = last_wall = clock.now()
    next_snap = start
    try:
        while not stop:
            if remote or machines:
                world.pump()
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
            if view is not None and now >= next_snap:
                next_snap = now + args.snapshot_period
                write()
            if args.quit_after_game and game.phase == "POST_GAME":
                break
            node.channels.public.wait(LOOP_PERIOD)
    except WorldLost as exc:
        lost = exc
    finally:
        for s, h in old.items():
            signal.signal(s, h)
        node.close()
        _close(world)
        if view is not None:
            write()
        if msglog is not None:
            msglog.close()
    print(f"final score: {_score(game)} ({game.phase}"
          + (f", stopped by signal {stop[0]}" if stop else "")
          + (", the world was lost" if lost else "") + ")", file=out, flush=True)
    for color, name in game.teams.items():
        if name:
            t = game.tally(color)
            print(f"{name} ({color}): stations broken {t.broken_total}"
                  + "".join(f", {k} {v}" for k, v in t.broken.items())
                  + f"; referee calls {sum(c['count'] for c in t.referee.values())}"
                  + "".join(f", {k} {c['count']} ({c['penalty']:+d})" for k, c in t.referee.items()),
                  file=out, flush=True)
    if lost is not None:
        raise Unavailable(f"{lost}; the refbox stops", where="--world")
    return 0


def _stored_game(game, stored, args) -> None:
    """``--game``: the game plays the stored one; ``--save-game``: it is written."""
    from .stored_game import play_stored, store_game
    if stored is not None:
        try:
            play_stored(game, stored)
        except ValueError as exc:
            raise UserError(str(exc), where="--game") from None
    if args.save_game:
        try:
            store_game(game, name=stored.name if stored is not None else "").save(args.save_game)
        except OSError as exc:
            raise UserError(f"cannot write the stored game: {exc}", where="--save-game") from None


def _close(world) -> None:
    close = getattr(world, "close", None)
    if close is not None:
        close()
