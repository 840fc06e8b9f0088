"""``rll-bt sim --external-team COLOR --teamserver HOST:PORT``: the league's
simulator for other teams' software (see :mod:`games.league_sim`).

The simulated robots of each colour named connect to that team's team
server (TCP, plain protobuf_comm frames: AgentTask in, BeaconSignal out) and
the simulated refbox talks UDP on the refbox's default ports, broadcast on
loopback; the game starts once every robot is connected and runs on the
wall clock.  Two colours: two teams' software play each other.
"""
from __future__ import annotations

import argparse
import sys

from rll_bt.errors import Unavailable, UserError

EXTERNAL_PORT = 2016          # the league simulator's robots connect here by default
DEFAULT_NAMES = {"CYAN": ("GRIPS", "rll-bt-sim-key"), "MAGENTA": ("Opponent", "rll-bt-sim-key-magenta")}


def _hostport(text: str) -> tuple[str, int]:
    host, sep, port = text.rpartition(":")
    if not sep:
        host, port = text, str(EXTERNAL_PORT)
    try:
        value = int(port)
    except ValueError:
        value = -1
    if not host or not 0 < value < 65536:
        raise argparse.ArgumentTypeError(f"expected HOST:PORT, got {text!r}")
    return host, value


def add_arguments(parser) -> None:
    g = parser.add_argument_group("other teams' software (the league's simulator; docs/league.md)")
    g.add_argument("--external-team", action="append", default=[], type=str.upper, choices=("CYAN", "MAGENTA"),
                   metavar="COLOR", help="the robots of COLOR (cyan/magenta) connect to a team server of the "
                                         "league (AgentTask); repeat for two teams")
    g.add_argument("--teamserver", action="append", default=[], type=_hostport, metavar="HOST:PORT",
                   help=f"that team's team server, one per --external-team in the same order "
                        f"(default 127.0.0.1:{EXTERNAL_PORT})")
    for color in ("cyan", "magenta"):
        name, key = DEFAULT_NAMES[color.upper()]
        g.add_argument(f"--team-{color}", metavar="NAME", default=name,
                       help=f"the {color} team's name as the refbox knows it (default {name})")
        g.add_argument(f"--key-{color}", metavar="KEY", default=key,
                       help=f"the {color} team's crypto key (default {key})")
    g.add_argument("--refbox-broadcast", default="127.255.255.255", metavar="HOST",
                   help="where the refbox sends (default the loopback broadcast, so every team server on this "
                        "machine hears it)")
    g.add_argument("--refbox-ports", default="sim", choices=("sim", "competition"),
                   help="the refbox's port layout (default sim: public 4444/4445, cyan 4441/4446, "
                        "magenta 4442/4447, refbox sends/listens)")
    g.add_argument("--connect-timeout", type=float, default=120.0, metavar="S",
                   help="exit 3 when the robots are not all connected after S seconds (default 120)")


def run(args) -> int:
    from rll_bt.agent import check_team_key
    from rll_bt.comm import layout as get_layout

    from .league_sim import ExternalGame, ExternalTeam
    from .progress import ProgressBar
    colors = args.external_team
    if len(set(colors)) != len(colors):
        raise UserError("each colour at most once", where="--external-team")
    servers = list(args.teamserver)
    if len(servers) > len(colors):
        raise UserError(f"{len(servers)} team servers for {len(colors)} external teams", where="--teamserver",
                        hint="give one --teamserver per --external-team, in the same order")
    servers += [("127.0.0.1", EXTERNAL_PORT)] * (len(colors) - len(servers))
    teams = []
    for color, server in zip(colors, servers):
        name, key = getattr(args, f"team_{color.lower()}"), getattr(args, f"key_{color.lower()}")
        try:
            check_team_key(key)
        except ValueError as exc:
            raise UserError(str(exc), where=f"--key-{color.lower()}") from None
        teams.append(ExternalTeam(color, server, name, key, robots=args.robots))
    offset = int(args.refbox_port_offset)
    if not 0 <= offset <= 60000:
        raise UserError(f"must be 0..60000, not {offset}", where="--refbox-port-offset")
    speed = 1.0 if args.speed is None else float(args.speed)
    if not speed > 0:
        raise UserError("the league's simulator runs on the wall clock: give --speed X > 0 (game seconds per wall "
                        "second; default 1)", where="--speed")
    phases = {k: float(v) for k in ("setup", "exploration", "production") if (v := getattr(args, k)) is not None}
    try:
        game = ExternalGame(teams, profile=args.profile, seed=args.seed, host=args.refbox_broadcast,
                            layout=get_layout(args.refbox_ports).moved(offset), phases=phases,
                            perception=args.perception, hz=args.hz, localisation=args.localisation, world_step=0.05,
                            speed=speed)
    except OSError as exc:
        raise Unavailable(f"cannot open the refbox's UDP ports: {exc}", where=f"--refbox-ports {args.refbox_ports}"
                          + (f" --refbox-port-offset {offset}" if offset else ""),
                          hint="is another refbox running on this machine?") from None
    say = (lambda text: None) if args.quiet else (lambda text: print(f"rll-bt sim: {text}", file=sys.stderr,
                                                                      flush=True))
    try:
        for t in teams:
            say(f"{t.color.lower()}: {t.robots} robot(s) of {t.name} connecting to {t.server[0]}:{t.server[1]}")
        shown = [-1]

        def connecting(connected):
            if len(connected) != shown[0]:
                shown[0] = len(connected)
                say(f"{len(connected)}/{len(game.agents)} robots connected")
        if not game.connect(args.connect_timeout, progress=connecting):
            missing = sorted(set(game.agents) - set(game.connected()))
            raise Unavailable(f"robots {', '.join(f'{c.lower()} {n}' for c, n in missing)} could not connect "
                              f"within {args.connect_timeout:g} s", where="--teamserver",
                              hint="is the team server listening there?")
        say("game started (refbox on UDP, broadcast to " f"{args.refbox_broadcast}, ports {game.layout.name})")
        bar = None if args.quiet else ProgressBar(sum(_lengths(game, phases)), team=teams[0].color)
        finished = game.run(progress=bar)
        status = game.status()
        if bar is not None:
            bar.done(game.clock.now(), status)
        for t in teams:
            print(f"{t.color.lower():8} {t.name:20} {status.points.get(t.color, 0):5d} points")
        return 0 if finished else 1
    finally:
        game.close()


def _lengths(game, phases: dict) -> list[float]:
    p = game.world.profile.phases
    return [phases.get("setup", p.setup), phases.get("production", p.production)
            + (0.0 if p.exploration_in_production > 0 else phases.get("exploration", p.exploration))]
