"""``rll-bt agent``: run one robot's agent on the wall clock with real sockets.

It opens the backend, connects to the team server over the encrypted TCP
link (reconnecting with backoff), joins the refbox's public channel and,
once the colour is known, its team channel, and runs tasks (the league's
AgentTask) as trees until stopped (Ctrl-C or SIGTERM stop the robot
first).  With ``--league`` the team server may be any that speaks the
league's AgentTask: plain frames, only AgentTask and BeaconSignal.

Exit codes: 0 stopped normally (or ``--seconds`` elapsed), 2 bad arguments
(a malformed key, port or address, an invalid tree), 3 unreachable (the
backend, the refbox ports, or the team server within ``--connect-timeout``),
130 interrupted.
"""
from __future__ import annotations

import argparse
import signal
import socket
import sys
from pathlib import Path

from ..errors import Unavailable, UserError
from .argtypes import seconds as _nonneg_float
from .argtypes import share as _share
from .refbox import _port, _positive_float, _positive_int
from .tree import _kv, _pose

EXIT_OK, EXIT_INTERRUPTED = 0, 130


def _hostport(text: str) -> tuple[str, int]:
    """HOST:PORT, or HOST alone for the default port."""
    host, sep, port = text.rpartition(":")
    if not sep:
        from ..comm import TEAM_SERVER_PORT
        host, port = text, str(TEAM_SERVER_PORT)
    if not host or not port:
        raise argparse.ArgumentTypeError(f"expected HOST:PORT, got {text!r}")
    return host, _port(port)


def register(cli) -> None:
    from ..comm import DEFAULT_HOST, LAYOUTS, TEAM_SERVER_PORT
    from ..plugins import Choices
    p = cli.command("agent", help="run a robot agent: team-server tasks as behaviour trees on a backend")
    p.description = ("Run one robot's agent on the wall clock with real sockets. "
                     + __doc__.split("\n\n")[1].replace("\n", " "))
    p.epilog = "exit codes: 0 stopped, 2 bad arguments, 3 backend/refbox/team server unreachable, 130 interrupted"
    g = p.add_argument_group("robot and team")
    g.add_argument("--robot", type=_positive_int, required=True, metavar="N", help="jersey number (1, 2, 3 ...)")
    g.add_argument("--team", required=True, metavar="NAME", help="team name exactly as configured in the refbox")
    g.add_argument("--key", required=True, metavar="KEY",
                   help="the team key (printable ASCII, no blanks): encrypts the team-server link and "
                        "the refbox team channel")
    g.add_argument("--name", metavar="PEER", help="robot name in beacons (default R<N>)")
    g.add_argument("--profile", default="rcll2016", choices=("rcll2016", "rcll2025"),
                   help="rules profile and refbox message set (default rcll2016)")
    g.add_argument("--color", choices=("cyan", "magenta"),
                   help="team colour (default: learnt from the refbox's GameState or the team server)")
    g = p.add_argument_group("robot backend")
    g.add_argument("--backend", required=True, metavar="NAME", help="backend (rll_bt.backends entry point)")
    g.add_argument("--backend-opt", action="append", type=_kv, default=[], metavar="K=V",
                   help="backend option (value read as YAML), repeatable")
    g.add_argument("--robot-config", type=Path, metavar="FILE",
                   help="robot configuration (YAML: base, laser, camera, gripper, their ports and mounting "
                        "poses) for the robotino backend")
    g.add_argument("--start-pose", type=_pose, metavar="X,Y,THETA",
                   help="field pose at start, for backends that only know odometry (without it the robot "
                        "localises globally)")
    g = p.add_argument_group("team server")
    g.add_argument("--teamserver", type=_hostport, default=("127.0.0.1", TEAM_SERVER_PORT), metavar="HOST:PORT",
                   help=f"team server address (default 127.0.0.1:{TEAM_SERVER_PORT})")
    g.add_argument("--connect-timeout", type=_positive_float, metavar="S",
                   help="exit 3 if the team server cannot be reached within S seconds (default: keep trying)")
    g.add_argument("--first-start", action="store_true",
                   help="the first RobotHello says restarted=false (default: true, the agent has no memory "
                        "of earlier tasks)")
    g.add_argument("--league", action="store_true",
                   help="the team server speaks only the league's messages (AgentTask in, BeaconSignal out, "
                        "plain frames, as the league's simulator's robots): no rll-bt additions, the stations "
                        "found from the refbox's MachineInfo and the robot's own sightings (with --no-refbox the "
                        "robot runs every task it gets: nothing else says whether the game runs)")
    g = p.add_argument_group(
        "network faults (testing)", "emulate a lossy radio on this agent's team-server link, both ways "
        "(the refbox channels stay as they are)")
    g.add_argument("--net-loss", type=_share, default=0.0, metavar="P", help="share of TCP segments lost (default 0)")
    g.add_argument("--net-delay", type=_nonneg_float, default=0.0, metavar="S", help="one-way delay (default 0)")
    g.add_argument("--net-jitter", type=_nonneg_float, default=0.0, metavar="S",
                   help="standard deviation of the delay (default 0)")
    g.add_argument("--net-bandwidth", type=_positive_float, metavar="BIT/S", help="bandwidth cap per direction")
    g.add_argument("--net-cut", action="append", type=_interval, default=[], metavar="T0-T1",
                   help="no link from T0 to T1 s after the agent started, repeatable")
    g.add_argument("--net-seed", default="0", metavar="SEED", help="seed of the faults (default 0)")
    g = p.add_argument_group("refbox")
    g.add_argument("--refbox-host", default=DEFAULT_HOST, metavar="HOST",
                   help=f"where refbox broadcasts go, e.g. a broadcast address (default {DEFAULT_HOST})")
    g.add_argument("--layout", choices=sorted(LAYOUTS), default="competition",
                   help="refbox ports: competition (4444/4441/4442) or sim (split local ports)")
    for chan in ("public", "team"):
        g.add_argument(f"--{chan}-recv", type=_port, metavar="N", help=f"port to listen on for the {chan} channel")
        g.add_argument(f"--{chan}-send", type=_port, metavar="N", help=f"port to send to on the {chan} channel")
    g.add_argument("--no-refbox", action="store_true",
                   help="do not join the refbox channels (no beacons; game state from the team server only)")
    g = p.add_argument_group("running")
    g.add_argument("--trees", type=Path, metavar="DIR",
                   help="directory of <task kind>.yaml (default: installed trees/)")
    g.add_argument("--hz", type=_positive_float, default=10.0, help="tree tick rate in Hz (default 10)")
    g.add_argument("--localisation", default="standard", metavar="PRESET",
                   choices=Choices("rll_bt.nodes", "localisation"),   # published by the skills' entry point
                   help="localiser preset (%(choices)s): standard (accuracy; the default) or cheap (fewer "
                        "particles and beams, for several simulated robots on one machine)")
    g.add_argument("--seconds", type=_positive_float, metavar="S", help="stop after S seconds")
    g.add_argument("-q", "--quiet", action="store_true", help="no progress lines")
    from .watching import add_options
    add_options(p, "the robot: its pose, laser scans, camera frames, detections, every tick of its task "
                   "trees and every message it sends and receives (team-server link and refbox channels)",
                camera=True)
    p.set_defaults(func=cmd_agent)


def _interval(text: str) -> tuple[float, float]:
    from ..comm.faults import parse_cut
    try:
        _, a, b = parse_cut(f"this:{text}")
    except ValueError:
        raise argparse.ArgumentTypeError(f"a cut is T0-T1 in seconds (e.g. 30-45), not {text!r}") from None
    return a, b


def _faulty(args, link, robot: int, clock):
    """``link`` behind the --net-* faults (cut times from now), or as it is."""
    from ..comm.faults import FaultyTransport, NetFaults
    net = NetFaults(loss=args.net_loss, delay=args.net_delay, jitter=args.net_jitter, bandwidth=args.net_bandwidth,
                    cuts=tuple(("all", a, b) for a, b in args.net_cut))
    faults = net.for_robot(robot, offset=clock.now())
    if faults is None:
        return link
    return FaultyTransport(link, faults, seed=f"{args.net_seed}/R{robot}", clock=clock, stream=True)


def _config(args):
    from ..agent import AgentConfig, check_team_key
    try:
        check_team_key(args.key)
    except ValueError as exc:
        raise UserError(str(exc), where="--key",
                        hint="give the key from the refbox's crypto-keys for your team") from None
    if args.trees is not None and not args.trees.is_dir():
        raise UserError("not a directory", where=f"--trees {args.trees}", hint="give the directory of the trees")
    try:
        return AgentConfig(robot_id=args.robot, team_name=args.team, peer_name=args.name or "",
                           profile=args.profile, color=args.color, trees_dir=args.trees, hz=args.hz,
                           league_only=args.league,
                           # nothing but the refbox could say whether the game runs: the league's team server decides
                           require_game=not (args.league and args.no_refbox))
    except ValueError as exc:
        raise UserError(str(exc)) from None


def _check_trees(trees_dir: Path | None) -> tuple[list[str], list[str]]:
    """The task kinds without a tree, and what the trees lack of the outputs
    the agent reads (an invalid tree stops the start)."""
    from ..agent import TREE_KINDS, output_problems
    from ..tree import TreeLoadError, parse_tree
    if trees_dir is None:
        raise UserError("no trees directory found", where="--trees", hint="give --trees DIR")
    missing: list[str] = []
    notes: list[str] = []
    for kind in TREE_KINDS:
        path = trees_dir / f"{kind}.yaml"
        if not path.is_file():
            missing.append(kind)
            continue
        try:
            spec = parse_tree(path, search_path=[trees_dir])
        except TreeLoadError as exc:
            raise UserError(f"invalid tree:\n{exc}", where=str(path),
                            hint="fix it (rll-bt tree validate) or point --trees elsewhere") from None
        notes.extend(output_problems(kind, spec))
    return missing, notes


def _resolve(host: str, what: str) -> None:
    try:
        socket.getaddrinfo(host, None, socket.AF_INET)
    except OSError as exc:
        raise Unavailable(f"cannot resolve {host!r}: {exc}", where=what) from None


def _say(args, text: str) -> None:
    if not args.quiet:
        print(f"rll-bt agent: {text}", file=sys.stderr, flush=True)


def _open_refbox(args, config, clock):
    from ..agent import RefboxAddress, refbox_channels
    if args.no_refbox:
        return None, None
    _resolve(args.refbox_host, "--refbox-host")
    addr = RefboxAddress(args.refbox_host, args.layout, args.public_recv, args.public_send, args.team_recv,
                         args.team_send)
    try:
        return refbox_channels(addr, config.profile, key=args.key, clock=clock)
    except OSError as exc:
        raise Unavailable(f"cannot open the refbox UDP channels: {exc}", where=f"--refbox-host {args.refbox_host}",
                          hint="is the port free (another robot on this host needs --layout sim or other ports)?"
                          ) from None


def cmd_agent(args) -> int:
    from ..agent import RobotAgent, default_trees_dir, team_server_link
    from ..clock import WallClock
    from ..watch.process import watch_agent
    from .tree import _backend
    from .watching import close_watch, open_watch
    config = _config(args)
    trees_dir = config.trees_dir or default_trees_dir()
    missing, notes = _check_trees(trees_dir)
    if missing:
        _say(args, f"no tree for {', '.join(missing)} in {trees_dir} (such tasks will fail with INVALID_TASK)")
    for note in notes:
        _say(args, note)
    host, port = args.teamserver
    _resolve(host, "--teamserver")
    clock = WallClock()
    backend = _backend(args, clock)
    link = public = agent = watch = None
    try:
        public, team = _open_refbox(args, config, clock)
        link = _faulty(args, team_server_link(host, port, key=None if args.league else args.key, clock=clock),
                       config.robot_id, clock)
        watch = open_watch(args, f"rll-bt agent R{config.robot_id} ({config.profile})",
                           {"kind": "agent", "robot": config.robot_id, "team": config.team_name,
                            "profile": config.profile})
        robot_watch = None
        if watch is not None:
            robot_watch, backend_used, link, public, team = watch_agent(
                watch, config.robot_id, backend, link, public, team, camera_hz=args.record_camera or 0.0)
        else:
            backend_used = backend
        agent = RobotAgent(config, clock=clock, backend=backend_used, link=link, public=public, team=team,
                           services={"localisation": args.localisation},
                           start_pose=args.start_pose, restarted=not args.first_start)
        if robot_watch is not None:
            robot_watch.attach(agent)
        _say(args, f"robot {config.robot_id} ({config.peer_name}) of {config.team_name}, backend {args.backend}, "
                   f"team server {host}:{port}, trees {trees_dir}, localisation {args.localisation}")
        return _loop(args, agent, clock, host, port)
    finally:
        if agent is not None:
            agent.link.close()
            agent.refbox.close()
        else:
            for t in (link, public):
                if t is not None:
                    t.close()
        try:
            backend.stop()
        except Exception:
            pass
        backend.close()
        close_watch(watch, args)


class _Stop(BaseException):
    """SIGTERM, raised wherever the agent is (as KeyboardInterrupt): no tree's
    ``except Exception`` takes it for a failing node."""


def _loop(args, agent, clock, host: str, port: int) -> int:
    def on_term(signum, frame):
        raise _Stop()
    old = signal.signal(signal.SIGTERM, on_term) if _main_thread() else None
    start = clock.now()
    last_note = start
    was_connected = False
    rc = EXIT_OK
    try:
        while True:
            agent.step()
            now = clock.now()
            if agent.connected != was_connected:
                was_connected = agent.connected
                _say(args, f"team server {host}:{port} " + ("connected" if was_connected else
                                                            "not connected; retrying with backoff"))
            if not was_connected and args.connect_timeout and agent.registrations == 0 and \
                    now - start > args.connect_timeout:
                raise Unavailable(f"no connection to the team server within {args.connect_timeout:g} s",
                                  where=f"--teamserver {host}:{port}", hint="is the team server running?")
            if now - last_note >= 10.0:
                last_note = now
                run = agent.run
                _say(args, f"{agent.state()}  game {agent.gate.describe()}" +
                     (f"  task {run.task_id} {run.kind}" if run is not None else ""))
            if args.seconds and now - start >= args.seconds:
                break
            agent.wait(0.05)
    except (KeyboardInterrupt, _Stop) as exc:
        rc = EXIT_INTERRUPTED if isinstance(exc, KeyboardInterrupt) else EXIT_OK
        _say(args, "stopping")
    finally:
        agent.shutdown()
        if old is not None:
            signal.signal(signal.SIGTERM, old)
    return rc


def _main_thread() -> bool:
    import threading
    return threading.current_thread() is threading.main_thread()
