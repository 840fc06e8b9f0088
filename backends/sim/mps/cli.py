"""``rll-bt sim stations``: serve a world's stations to a real refbox.

    rll-bt sim stations --profile rcll2025 --seed 1 --mqtt 127.0.0.1:1883
    rll-bt sim stations --broker amqtt            # start a broker on 1883 too
    rll-bt sim stations --opcua                   # one OPC-UA PLC per station, 4840..4856

The world runs on the wall clock (``--rate`` world seconds per second);
each command a station gets and each thing it does is printed as one line.
Robots are not in this world: a workpiece reaches a station's input only
through the station itself (a base dispensed, a product retrieved from
storage) or a program using the world's station API.
"""
from __future__ import annotations

import sys
import time

from rll_bt.errors import Unavailable, UserError


def register(cli) -> None:
    sub = cli.group("sim")
    p = sub.add_parser(
        "stations", help="serve a world's stations as machines to a real refbox (MQTT, OPC-UA)",
        description="Build a world and serve its stations as the machines a real refbox drives: "
                    "over the refbox's MQTT machine topics through a broker (--mqtt, --broker) "
                    "and/or as Festo PLCs over OPC-UA (--opcua).  Runs until --duration or Ctrl-C.")
    p.add_argument("--profile", default="rcll2025", help="rules profile (default: %(default)s)")
    p.add_argument("--seed", type=int, default=0, help="field layout seed (default: %(default)s)")
    p.add_argument("--game", metavar="FILE",
                   help="build the field of a stored game (rll-bt JSON, or a refbox archive of game reports: "
                        "its first game); its ring stations' feeders hold the game's colours")
    p.add_argument("--machines", metavar="LIST",
                   help="comma-separated stations to serve (default: all of the world's)")
    p.add_argument("--mqtt", metavar="HOST:PORT", help="serve over MQTT through this broker")
    p.add_argument("--broker", choices=("amqtt", "mosquitto", "auto"),
                   help="start a broker (on --mqtt's address, default 127.0.0.1:1883) and serve through it")
    p.add_argument("--opcua", action="store_true", help="serve each station as an OPC-UA PLC")
    p.add_argument("--opcua-host", default="127.0.0.1", help="OPC-UA address (default: %(default)s)")
    p.add_argument("--opcua-base-port", type=int, default=4840,
                   help="C-BS's port; C-x at base+0..6, M-x at base+10..16 (default: %(default)s)")
    p.add_argument("--device", choices=("plc", "codesys"), default="plc",
                   help="OPC-UA node names: the Festo PLC's (connection: plc) or CODESYS's "
                        "(connection: plc_simulation) (default: %(default)s)")
    p.add_argument("--opcua-response-delay", type=float, default=20.0, metavar="MS",
                   help="hold each OPC-UA read and write answer this long, so the refbox's freeopcua "
                        "client cannot miss it (see docs/league.md; default: %(default)s ms, 0: at once)")
    p.add_argument("--rate", type=float, default=1.0,
                   help="world seconds per wall second (default: %(default)s)")
    p.add_argument("--duration", type=float, metavar="S", help="stop after S world seconds")
    p.add_argument("--time-step", type=float, default=0.02, help="world step (default: %(default)s s)")
    p.set_defaults(func=run_stations)


def _hostport(text: str, default_port: int) -> tuple[str, int]:
    host, _, port = text.rpartition(":") if ":" in text else (text, "", str(default_port))
    try:
        return host or "127.0.0.1", int(port)
    except ValueError:
        raise UserError(f"not HOST:PORT: {text!r}", where="--mqtt") from None


def _stop_on_sigterm() -> None:
    """SIGTERM ends the command like Ctrl-C, so the broker it started is stopped too."""
    import signal

    def interrupt(signum, frame):
        raise KeyboardInterrupt
    signal.signal(signal.SIGTERM, interrupt)


def run_stations(args) -> int:
    from rll_bt import rules

    from ..world import World
    from . import Broker, BrokerError, MachineHall, MqttMachines, OpcuaMachines
    if not (args.mqtt or args.broker or args.opcua):
        raise UserError("nothing to serve: give --mqtt HOST:PORT, --broker or --opcua")
    if args.rate <= 0 or args.time_step <= 0:
        raise UserError("--rate and --time-step must be > 0")
    try:
        profile = rules.profile(args.profile)
    except ValueError as exc:
        raise UserError(str(exc), where="--profile") from None
    layout, feeders = None, None
    if args.game:
        from ..stored import StoredGameError, load_game
        try:
            game = load_game(args.game)
        except StoredGameError as exc:
            raise UserError(str(exc), where="--game") from None
        if game.profile != profile.name:
            raise UserError(f"the stored game is {game.profile}, not {profile.name}", where="--game")
        layout, feeders = game.layout(args.seed), dict(game.ring_colors)
    world = World(profile, seed=args.seed, layout=layout)
    machines = args.machines.split(",") if args.machines else None
    try:
        hall = MachineHall(world, machines, feeders=feeders)
    except KeyError as exc:
        world.close()
        raise UserError(str(exc.args[0]), where="--machines") from None
    opened: list = []
    _stop_on_sigterm()
    try:
        if args.broker:
            host, port = _hostport(args.mqtt or "127.0.0.1:1883", 1883)
            try:
                opened.append(Broker(args.broker, host, port))
            except BrokerError as exc:
                raise Unavailable(str(exc)) from None
            print(f"broker {opened[-1].kind} on {host}:{port}", file=sys.stderr)
        if args.mqtt or args.broker:
            host, port = _hostport(args.mqtt or "127.0.0.1:1883", 1883)
            try:
                opened.append(MqttMachines(hall, host, port).start())
            except ConnectionError as exc:
                raise Unavailable(str(exc)) from None
            print(f"stations on MQTT {host}:{port}: {', '.join(hall.machines)}", file=sys.stderr)
        if args.opcua:
            if not 0 <= args.opcua_response_delay <= 1000:
                raise UserError(f"must be 0..1000 ms, not {args.opcua_response_delay}", where="--opcua-response-delay")
            served = OpcuaMachines(hall, args.opcua_host, base_port=args.opcua_base_port, device=args.device,
                                   progress=lambda line: print(line, file=sys.stderr, flush=True),
                                   response_delay=args.opcua_response_delay / 1000.0)
            try:
                opened.append(served.start())
            except OSError as exc:
                raise Unavailable(str(exc)) from None
            print("stations on OPC-UA: " + ", ".join(f"{m} {p}" for m, p in served.ports.items()),
                  file=sys.stderr)
        return _loop(world, hall, args)
    finally:
        for thing in reversed(opened):
            thing.stop()
        world.close()


def _loop(world, hall, args) -> int:
    printed = dict.fromkeys(hall.machines, 0)
    t0, w0 = time.monotonic(), world.time
    while args.duration is None or world.time - w0 < args.duration:
        hall.update()
        for m in hall:
            for rec in m.records[printed[m.name]:]:
                print(f"{rec.time:9.2f} {m.name:6} {rec.text}", flush=True)
            printed[m.name] = len(m.records)
        ahead = (world.time - w0) / args.rate - (time.monotonic() - t0)
        if ahead > 0:
            time.sleep(ahead)
        world.step(args.time_step)
    return 0


__all__ = ["register", "run_stations"]
