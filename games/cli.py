"""``rll-bt sim``: play a whole simulated game and report it.

    rll-bt sim --seed 3                       # lockstep, headless, 2016 rules
    rll-bt sim --profile rcll2025 --out game/ # + messages.jsonl, report.json, PNGs
    rll-bt sim --processes                    # refbox, world, team server, agents as processes
    rll-bt sim --refbox external --refbox-host H   # against a refbox that runs already (the real one)
    rll-bt sim --cyan htn --magenta baseline  # two teams on one field (CONFIG: games.teams)

By default everything runs in one process on one simulated clock (refbox,
world, team server and agents; messages cross an in-process bus as encoded
frames).  ``--processes`` runs the simulated refbox, the team server and
every agent as processes of their own talking over loopback UDP and TCP on
the wall clock, as in a real game; this process keeps the world, serving
the agents' backends and the refbox's stations (the station link) over TCP.  The SETUP phase is shortened to
``--setup`` seconds (default 10): nothing happens in it in simulation.

``--refbox external`` plays against a refbox that runs already (the
league's, or ``rll-bt refbox sim``): the world serves it its stations and
its clock, the team server and the agents play on its ports
(:mod:`games.external`, ``docs/league.md``).
``--external-team COLOR --teamserver HOST:PORT`` makes the world the
league's simulator for another team's software: the robots of COLOR
connect to that team server and take its AgentTasks (:mod:`games.league_sim`).

Exit codes: 0 the game finished, 1 it did not, 2 bad arguments, 3 no display
for ``--gui``, the external refbox (or its broker) cannot be reached, or an
external team's robots could not connect.
``rll-bt sim world`` (the world's own command) draws layouts.

Registered through the ``rll_bt.commands`` entry point ``games``.  The
values of ``--perception``, ``--strategy`` and ``--localisation`` are the
ones the simulator, the team server and the skills publish
(:mod:`games.options`).
"""
from __future__ import annotations

import argparse
import errno
import sys
from pathlib import Path

from rll_bt.cli.argtypes import seconds as _seconds
from rll_bt.cli.argtypes import share as _fraction
from rll_bt.errors import Unavailable, UserError


def _positive(text: str) -> float:
    v = _seconds(text)
    if v <= 0:
        raise argparse.ArgumentTypeError(f"must be > 0, not {text}")
    return v


DEFAULT_VIEW_PORT = 8766


def _cut(text: str) -> tuple[str, float, float]:
    from rll_bt.comm.faults import parse_cut
    try:
        return parse_cut(text)
    except ValueError as exc:
        raise argparse.ArgumentTypeError(str(exc)) from None


def register(cli) -> None:
    from rll_bt import rules
    from rll_bt.plugins import Choices

    from .options import LASERS, PUBLISHED, UNTIL

    def published(option: str):       # loaded only when a value is checked or --help shown
        group, _field = PUBLISHED[option]
        return Choices(group, option)
    cli.group("sim")
    gp = cli.group_parser("sim")
    gp.description = __doc__.split("\n\n")[2].replace("\n", " ")
    gp.epilog = ("exit codes: 0 game finished, 1 it did not, 2 bad arguments, 3 no display for --gui, the "
                 "external refbox unreachable or an external team's robots could not connect, 130 interrupted")
    g = gp.add_argument_group("game")
    g.add_argument("--profile", default=rules.DEFAULT, choices=rules.PROFILES,
                   help="rules profile (default %(default)s)")
    g.add_argument("--robots", type=int, default=3, choices=(1, 2, 3), help="robots in our team (default 3)")
    g.add_argument("--seed", type=int, default=1, help="seed of layout, lights, orders and noise (default 1)")
    g.add_argument("--perception", default="oracle", choices=published("perception"), metavar="MODE",
                   help="the simulator's perception (%(choices)s; default %(default)s): oracle: the "
                        "simulator reports tags and lights; rendered: detectors on camera images")
    g.add_argument("--strategy", default="algorithm1", choices=published("strategy"), metavar="NAME",
                   help="exploration strategy of the team server (%(choices)s; default %(default)s)")
    g.add_argument("--baseline", action="store_true",
                   help="greedy one-order-at-a-time production instead of the HTN planner")
    g.add_argument("--cyan", metavar="CONFIG",
                   help="the team playing cyan: htn, baseline, external (another team's software over the "
                        "refbox's network protocol; with --processes) or another team server, with settings "
                        "after a colon, e.g. htn:strategy=nearest,replan_period=5 or external:name=Caro,key=K; "
                        "without --cyan and --magenta our one team plays cyan (see docs/teams.md)")
    g.add_argument("--magenta", metavar="CONFIG", help="the team playing magenta, as --cyan")
    g.add_argument("--until", default="end", choices=UNTIL, help="stop after exploration or play to the end")
    g.add_argument("--setup", type=_seconds, default=10.0, metavar="S",
                   help="SETUP phase length in game seconds (default 10; the rules' 300 s change nothing here)")
    g.add_argument("--game", type=Path, metavar="FILE",
                   help="play a stored game: its field, orders, ring colours and costs and down periods "
                        "(JSON written by --save-game, or the first game of a refbox archive of game "
                        "reports such as rcll100.gz); the seed still fixes the rest (noise, 2016 light codes)")
    g.add_argument("--save-game", type=Path, metavar="FILE",
                   help="write this game's field, orders, ring setup and down periods to FILE (JSON) for --game")
    g.add_argument("--exploration", type=_seconds, metavar="S", help="exploration length (default: the rules')")
    g.add_argument("--production", type=_seconds, metavar="S", help="PRODUCTION length (default: the rules')")
    g.add_argument("--overtime", type=_seconds, metavar="S",
                   help="what a tie between two teams adds to PRODUCTION (default: the rules' 300 s; 0: a tie "
                        "ends the game, for short test games)")
    g = gp.add_argument_group("running")
    g.add_argument("--gui", action="store_true",
                   help="open PyBullet's window (needs a display); the game then runs in real time")
    g.add_argument("--out", type=Path, metavar="DIR",
                   help="write messages.jsonl, report.json, field.png, timeline.png, score.png here")
    g.add_argument("--processes", action="store_true",
                   help="the refbox, the team server and each agent as its own process over loopback "
                        "UDP/TCP on the wall clock, this process keeping the world (serving the "
                        "agents' backends and the refbox's stations over TCP); a whole game takes "
                        "the game's real length, --out keeps each process's log")
    g.add_argument("--hardware", default="none", choices=("none", "emulated"),
                   help="emulated: every agent runs the robotino backend (the code a real robot runs) on "
                        "device emulators fed by the world: base firmware and gripper on ptys, the laser "
                        "(--laser) and an MJPEG camera; implies --processes, detectors on camera frames")
    g.add_argument("--laser", default="urg", choices=LASERS,
                   help="the emulated laser with --hardware emulated: urg (Hokuyo URG-04LX, SCIP 2.0 on a pty, "
                        "the default), urg-tcp (Hokuyo UTM-30LX-EW, SCIP 2.0 on TCP) or tim (SICK TiM571, "
                        "CoLa on TCP)")
    g.add_argument("-q", "--quiet", action="store_true", help="no progress bar")
    g = gp.add_argument_group("a refbox elsewhere (the real one; docs/league.md)")
    g.add_argument("--refbox", default="simulated", choices=("simulated", "external"),
                   help="simulated: ours (default); external: a refbox that runs already at --refbox-host: "
                        "the world serves it its stations and its clock (SimTimeSync), the team server and "
                        "the agents play on its ports as processes (implies --processes); it draws the game")
    g.add_argument("--refbox-host", default="127.0.0.1", metavar="HOST",
                   help="the external refbox's host (default %(default)s)")
    g.add_argument("--refbox-port-offset", type=int, default=0, metavar="N",
                   help="its ports: the refbox's sim layout (TCP 4444, UDP 4444/4445, cyan 4441/4446) plus N; "
                        "with --external-team, where the simulator's refbox sends and listens")
    g.add_argument("--refbox-timeout", type=float, default=180.0, metavar="S",
                   help="seconds to wait for the refbox's stream and then for its field (default %(default)g)")
    g.add_argument("--refbox-control", default="auto", choices=("auto", "manual"),
                   help="auto (default): this game names the team, starts SETUP and switches to the next phase "
                        "once the robots are up; manual: a person drives the refbox")
    g.add_argument("--stations", default="mqtt", choices=("mqtt", "opcua"),
                   help="how the world's stations are served to it: mqtt (default, through --mqtt) or opcua "
                        "(a PLC per station from --opcua-base-port; start this before the refbox)")
    g.add_argument("--mqtt", metavar="HOST:PORT", help="the broker the refbox's stations use (default: the "
                                                       "refbox host's 1883)")
    g.add_argument("--opcua-base-port", type=int, default=4840, metavar="PORT",
                   help="C-BS's OPC-UA port; C-x at base+0..6, M-x at base+10..16 (default %(default)s)")
    g.add_argument("--team", default="GRIPS", metavar="NAME",
                   help="our team's name (default %(default)s; the external refbox's llsfrb/game/teams must list it)")
    g.add_argument("--key", default="rll-bt-sim-key", metavar="KEY",
                   help="our team's crypto key (default %(default)s; llsfrb/game/crypto-keys/NAME)")
    g = gp.add_argument_group("watching (Foxglove, see README)")
    g.add_argument("--record", type=Path, metavar="FILE.mcap",
                   help="record the game as MCAP: every refbox and team-server message, poses, scans, trees, "
                        "the field (open it in Foxglove; `rll-bt replay FILE` redraws the report)")
    g.add_argument("--live", type=int, nargs="?", const=8765, metavar="PORT",
                   help="serve the same channels over Foxglove's WebSocket protocol (default port 8765; "
                        "0: any free port); Foxglove: Open connection, ws://localhost:PORT")
    g.add_argument("--view", type=int, nargs="?", const=DEFAULT_VIEW_PORT, metavar="PORT",
                   help=f"serve the live page (field, robots, orders, score, trees) on http://localhost:PORT/ "
                        f"(default port {DEFAULT_VIEW_PORT}; 0: any free port)")
    g.add_argument("--speed", type=_seconds, metavar="X",
                   help="game seconds per wall second (1: real time, the default with --gui, --live or --view; "
                        "0: as fast as the machine goes, the default otherwise; with --external-team: > 0, "
                        "default 1)")
    g.add_argument("--record-camera", type=_seconds, default=0.0, metavar="HZ",
                   help="also take camera frames for the recording, per robot and second (default 0: only the "
                        "frames the robots' perception reads; a frame costs about 0.2 s of CPU)")
    g = gp.add_argument_group(
        "network faults", "a lossy radio on each robot's link to the team server (tasks, results, status, "
        "observations; both ways, seeded by --seed). The refbox's channels stay perfect. The link is TCP: "
        "a lost segment costs a retransmission, a cut drops the connection")
    g.add_argument("--net-loss", type=_fraction, default=0.0, metavar="P",
                   help="share of segments lost, e.g. 0.2 (default 0)")
    g.add_argument("--net-delay", type=_seconds, default=0.0, metavar="S", help="one-way delay (default 0)")
    g.add_argument("--net-jitter", type=_seconds, default=0.0, metavar="S",
                   help="standard deviation of the delay (default 0)")
    g.add_argument("--net-bandwidth", type=_positive, metavar="BIT/S", help="bandwidth cap per robot and direction")
    g.add_argument("--net-cut", type=_cut, action="append", default=[], metavar="ROBOT:T0-T1",
                   help="robot R<N> (or all) hears nothing and is not heard from T0 to T1 s after the game's "
                        "start (with --processes: after its agent started), repeatable")
    g = gp.add_argument_group("speed knobs")
    g.add_argument("--dt", type=_positive, default=0.05, metavar="S", help="lockstep step (default 0.05 s)")
    g.add_argument("--hz", type=_positive, default=10.0, help="tree tick rate of the agents (default 10)")
    g.add_argument("--laser-rate", type=_positive, default=10.0, metavar="HZ",
                   help="simulated laser scans per second (default 10)")
    g.add_argument("--localisation", default="cheap", choices=published("localisation"), metavar="PRESET",
                   help="localiser preset of the agents (%(choices)s; default %(default)s; with --processes "
                        "passed to every rll-bt agent)")
    from .external_cli import add_arguments
    add_arguments(gp)
    gp.set_defaults(func=run)

    p = cli.command("replay", "print what a game recording holds and draw its report again")
    p.description = ("Read an MCAP recording made with `rll-bt sim --record`: print its topics, schemas and "
                     "message counts and the game's result table, and draw field.png, timeline.png and "
                     "score.png from it.")
    p.add_argument("file", type=Path, metavar="FILE.mcap")
    p.add_argument("--out", type=Path, metavar="DIR",
                   help="where the PNGs go (default: FILE's folder / <FILE stem>_report)")
    p.add_argument("--no-png", action="store_true", help="only print the summary")
    p.set_defaults(func=replay)
    from .view.command import add
    add(cli)

    from .tournament.cli import register as register_tournament
    register_tournament(cli)


def options_from(args):
    from rll_bt.comm.faults import NetFaults

    from .options import GameOptions
    if args.game is not None and not args.game.is_file():
        raise UserError("no such file", where=f"--game {args.game}")
    if args.out is not None:
        try:
            args.out.mkdir(parents=True, exist_ok=True)
        except OSError as exc:
            raise UserError(f"cannot create the directory: {exc}", where=f"--out {args.out}") from None
    try:
        return GameOptions(profile=args.profile, robots=args.robots, seed=args.seed,
                           perception=args.perception, strategy=args.strategy, until=args.until,
                           gui=args.gui, out=args.out, processes=args.processes or args.hardware == "emulated",
                           hardware=args.hardware, laser=args.laser, setup=args.setup,
                           exploration=args.exploration, production=args.production, overtime=args.overtime, dt=args.dt,
                           hz=args.hz, laser_rate=args.laser_rate, localisation=args.localisation,
                           baseline=args.baseline, record=args.record, live=args.live,
                           record_camera=args.record_camera, view=args.view, speed=args.speed,
                           game=args.game, save_game=args.save_game,
                           refbox=args.refbox, refbox_host=args.refbox_host,
                           refbox_port_offset=args.refbox_port_offset, refbox_control=args.refbox_control,
                           refbox_timeout=args.refbox_timeout,
                           stations=args.stations, mqtt=args.mqtt, opcua_base_port=args.opcua_base_port,
                           team_name=args.team, key=args.key, cyan=args.cyan, magenta=args.magenta,
                           net=NetFaults(loss=args.net_loss, delay=args.net_delay, jitter=args.net_jitter,
                                         bandwidth=args.net_bandwidth, cuts=tuple(args.net_cut)))
    except ValueError as exc:
        raise UserError(str(exc)) from None


def run(args) -> int:
    if args.external_team:
        from .external_cli import run as run_external
        return run_external(args)
    if args.teamserver:
        raise UserError("--teamserver names the team server of an --external-team", where="--teamserver")
    from rll_bt.backend import BackendUnavailable
    from rll_bt.clock import WallClock

    from . import play
    options = options_from(args)
    if options.refbox == "external":
        options.processes = True
    if len(options.lineup()) > 1 and (options.record is not None or options.live is not None
                                      or options.view is not None):
        raise UserError("--record, --live and --view watch a game of one team", where="--magenta")
    if options.processes and (options.live is not None or options.view is not None):
        raise UserError("--live and --view serve a lockstep game; with --processes give --record (every process "
                        "records its part, merged into one file at the end) and replay it with rll-bt view FILE",
                        where="--processes")
    for name in ("live", "view"):
        port = getattr(options, name)
        if port is not None and not 0 <= port < 65536:
            raise UserError(f"not a port: {port}", where=f"--{name}")
    wall = WallClock()
    try:
        summary = play(options, progress=not args.quiet, clock=wall)
    except BackendUnavailable as exc:
        raise Unavailable(str(exc), where="--gui" if options.gui else None,
                          hint="leave out --gui to play headless, or run where DISPLAY (X11) or "
                               "WAYLAND_DISPLAY names a display") from None
    except OSError as exc:
        if options.view is None or exc.errno not in (errno.EADDRINUSE, errno.EACCES, errno.EADDRNOTAVAIL):
            raise
        raise Unavailable(f"cannot serve the live page: {exc.strerror}", where=f"--view {options.view}",
                          hint="another program on the port? give --view 0 for any free port") from None
    except RuntimeError as exc:
        if options.live is None or "bind" not in str(exc):
            raise
        raise Unavailable(f"cannot serve Foxglove's WebSocket: {exc}", where=f"--live {options.live}",
                          hint="another program on the port? give --live 0 for any free port") from None
    print(summary["table"])
    if options.out is not None:
        print(f"\nwrote {', '.join(summary['files'])} to {options.out}", file=sys.stderr)
    if options.record is not None:
        print(f"recorded {options.record} (rll-bt replay {options.record})", file=sys.stderr)
    return 0 if summary["finished"] else 1


def replay(args) -> int:
    from . import report
    from .replay import RecordingError, read, redraw, summary_lines
    if not args.file.is_file():
        raise UserError("file not found", where=str(args.file))
    try:
        rep = read(args.file)
    except RecordingError as exc:
        raise UserError(str(exc), where=str(args.file),
                        hint="give a recording made with rll-bt sim --record") from None
    for line in summary_lines(rep):
        print(line)
    if rep.recording.samples:
        options = rep.options()
        print()
        print(report.table(report.summarise(rep.game_result(), options)))
    if not args.no_png and rep.recording.samples:
        out = args.out or args.file.parent / f"{args.file.stem}_report"
        files = redraw(rep, out)
        print(f"\nwrote {', '.join(p.name for p in files)} to {out}", file=sys.stderr)
    return 0
