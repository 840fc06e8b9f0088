"""``rll-bt teamserver``: run the team server; ``rll-bt teamserver status``: look at it.

    rll-bt teamserver --profile rcll2016 --team Carologistics --key randomkey \\
        [--listen 0.0.0.0:4460] [--state teamserver.sqlite] [--strategy algorithm1] \\
        [--planner htn|greedy] [--robots rll-bt|agenttask] \\
        [--refbox-host 127.0.0.1] [--ports sim|competition] [--refbox-port-offset N]

The robots connect over TCP and take the league's AgentTask.  ``--robots
rll-bt`` (the default): rll-bt's agents, the link encrypted with the team
key, rll-bt's additions (machine map, game phase, observations) on it.
``--robots agenttask``: any robot that speaks the league's AgentTask (the
league's simulator's robots, ``rll-bt sim --external-team``): plain frames,
only AgentTask out and BeaconSignal / AgentTask in, default port 2016.
    rll-bt teamserver status [--state teamserver.sqlite]
"""
from __future__ import annotations

import argparse
import signal
import sys
import threading

from rll_bt import rules
from rll_bt.errors import Unavailable, UserError

DEFAULT_STATE = "teamserver.sqlite"
STRATEGIES = ("algorithm1", "algorithm1-paper", "random", "nearest")
PLANNER_NAMES = ("htn", "greedy")         # teamserver.planning.planner.PLANNERS
ROBOT_KINDS = ("rll-bt", "agenttask")
LISTEN = {"rll-bt": "0.0.0.0:4460", "agenttask": "0.0.0.0:2016"}


def register(cli) -> None:
    sub = cli.group("teamserver")
    gp = cli.group_parser("teamserver")
    gp.description = ("Run the team server: knowledge base, exploration, HTN production "
                      "planning and dispatch, between the refbox and the robots.  "
                      "'status' shows a server's state database.")
    gp.add_argument("--profile", default=rules.DEFAULT, choices=rules.PROFILES,
                    help="rules profile (default %(default)s)")
    gp.add_argument("--team", help="our team name, exactly as configured in the refbox")
    gp.add_argument("--key", help="the team's crypto key (team channel and robot link)")
    gp.add_argument("--listen", metavar="HOST:PORT",
                    help="where robots connect (default 0.0.0.0:4460, with --robots agenttask 0.0.0.0:2016)")
    gp.add_argument("--robots", default="rll-bt", choices=ROBOT_KINDS,
                    help="rll-bt: rll-bt's agents (encrypted link, rll-bt's additions); agenttask: any robot "
                         "that speaks the league's AgentTask (plain frames, the league's messages only) "
                         "(default %(default)s)")
    gp.add_argument("--state", default=DEFAULT_STATE, metavar="FILE",
                    help="SQLite state database; a restarted server resumes from it "
                         "(default %(default)s)")
    gp.add_argument("--strategy", default="algorithm1", choices=STRATEGIES,
                    help="exploration strategy (default %(default)s)")
    gp.add_argument("--planner", default="htn", choices=PLANNER_NAMES,
                    help="production planning: htn (several products at once, orders chosen "
                         "by simulating the plan) or greedy (one order at a time, earliest "
                         "deadline first; the benchmarks' baseline) (default %(default)s)")
    gp.add_argument("--seed", type=int, default=0, help="seed of the random choices")
    gp.add_argument("--refbox-host", default="127.0.0.1",
                    help="refbox address or broadcast address (default %(default)s)")
    gp.add_argument("--ports", default="sim", choices=("sim", "competition"),
                    help="refbox port layout: split local ports or one port per channel")
    gp.add_argument("--refbox-port-offset", type=int, default=0, metavar="N",
                    help="every port of that layout plus N (to play beside another refbox, e.g. "
                         "rll-bt sim --external-team ... --refbox-port-offset N) (default 0)")
    gp.add_argument("--color", choices=("CYAN", "MAGENTA"), type=str.upper,
                    help="force our colour (training games without team names)")
    gp.add_argument("--heartbeat-timeout", type=float, default=10.0, metavar="S",
                    help="drop a robot silent this long (default %(default)s s)")
    gp.add_argument("--beacon", type=int, metavar="NUMBER",
                    help="send a BeaconSignal of the team server with this jersey number")
    gp.add_argument("--duration", type=float, default=0.0, metavar="S",
                    help="stop after this many seconds (0: run until interrupted)")
    from rll_bt.cli.watching import add_options
    add_options(gp, "the team server's messages: every message it sends and receives on its link to the "
                    "robots and on the refbox's channels")
    gp.set_defaults(func=run)
    st = sub.add_parser("status", help="robots, tasks, orders and machines of a state database",
                        description="Print the robots, tasks, orders and known machines "
                                    "stored in a team server's state database.")
    st.add_argument("--state", default=DEFAULT_STATE, metavar="FILE",
                    help="the state database (default %(default)s)")
    st.add_argument("--recent", type=int, default=10, help="closed tasks to list")
    st.set_defaults(func=status)


def _host_port(text: str) -> tuple[str, int]:
    host, _, port = text.rpartition(":")
    try:
        p = int(port)
        if not 0 <= p < 65536:
            raise ValueError
    except ValueError:
        raise UserError(f"not HOST:PORT: {text!r}", where="--listen") from None
    return host or "0.0.0.0", p


def status(args: argparse.Namespace) -> int:
    from .status import load, render
    kb = load(args.state)
    try:
        print(render(kb, args.recent))
    finally:
        kb.store.close()
    return 0


def run(args: argparse.Namespace) -> int:
    if not args.team or not args.key:
        raise UserError("--team and --key are required to run the team server",
                        hint="rll-bt teamserver --team NAME --key KEY  (or: rll-bt teamserver "
                             "status)")
    from rll_bt.agenttask import link as agent_link
    from rll_bt.cli.watching import close_watch, open_watch
    from rll_bt.clock import WallClock
    from rll_bt.comm import layout
    from rll_bt.watch.process import watch_links

    from .links.refbox_link import udp_refbox_link
    from .server import ServerConfig, TeamServer

    offset = int(args.refbox_port_offset)
    if not 0 <= offset <= 60000:
        raise UserError(f"must be 0..60000, not {offset}", where="--refbox-port-offset")
    ports = layout(args.ports).moved(offset)
    listen = args.listen or LISTEN[args.robots]
    host, port = _host_port(listen)
    clock = WallClock()
    config = ServerConfig(strategy=args.strategy, seed=args.seed, planner=args.planner, robots=args.robots)
    config.dispatch.heartbeat_timeout = args.heartbeat_timeout
    if args.beacon is not None:
        config.beacon, config.beacon_number = True, args.beacon
    try:
        refbox = udp_refbox_link(args.profile, args.refbox_host, ports, clock)
    except OSError as exc:
        raise Unavailable(f"cannot open the refbox channels: {exc}",
                          where=f"{args.refbox_host} ({ports.name} ports)") from None
    try:
        agents = agent_link.tcp_server(port, host=host, clock=clock,
                                       key=args.key if args.robots == "rll-bt" else None)
    except OSError as exc:
        refbox.close()
        raise Unavailable(f"cannot listen for robots: {exc}", where=listen) from None
    try:
        watch = open_watch(args, f"rll-bt teamserver ({args.profile})",
                           {"kind": "teamserver", "team": args.team, "profile": args.profile})
    except BaseException:
        agents.close()
        refbox.close()
        raise
    if watch is not None:
        agents, refbox.public, refbox.team_factory = watch_links(
            watch, "teamserver", link=agents, public=refbox.public, team=refbox.team_factory)
    server = TeamServer(args.profile, args.team, clock=clock, refbox=refbox, agents=agents,
                        key=args.key, state=args.state, config=config, team_color=args.color)
    print(f"team server for {args.team} ({args.profile}) listening on {host}:{agents.port} for "
          f"{args.robots} robots, state in {args.state}", file=sys.stderr)
    start, last = clock.now(), -1e9
    old = signal.signal(signal.SIGTERM, _on_term) if threading.current_thread() is threading.main_thread() else None
    try:
        while not args.duration or clock.now() - start < args.duration:
            server.tick()
            agents.wait(0.05)
            if clock.now() - last >= 5.0:
                last = clock.now()
                print(_progress(server), file=sys.stderr)
    except _Stop:                  # SIGTERM: stop like at the end of --duration (the recording is closed)
        pass
    finally:
        if old is not None:
            signal.signal(signal.SIGTERM, old)
        agents.close()
        refbox.close()
        server.close()
        close_watch(watch, args)
    return 0


class _Stop(BaseException):
    """SIGTERM, raised wherever the server is."""


def _on_term(signum, frame):
    raise _Stop()


def _progress(server) -> str:
    kb = server.kb
    active = sum(1 for r in kb.robots.values() if r.status == "ACTIVE")
    open_tasks = len(kb.open_tasks())
    return (f"[{server.refbox.phase} {server.refbox.state} {server.refbox.game_time():6.1f} s] "
            f"colour {server.color or '?'}, robots {active}/{len(kb.robots)}, "
            f"open tasks {open_tasks}, points {kb.meta.get('points', 0)}")
