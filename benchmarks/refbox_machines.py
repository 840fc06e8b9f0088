"""Manual check: a REAL refbox drives the PyBullet world's stations over MQTT.

Not part of the suite (the refbox cannot be shipped with the project); run
it by hand against a refbox binary you built yourself (see
docs/league.md, "Playing against the real referee box")::

    python benchmarks/refbox_machines.py --refbox /path/to/rcll-refbox/bin/refbox

It starts an MQTT broker (amqtt), starts the refbox with every cyan station
``connection: mqtt`` on it (magenta stays mockup), names the team, goes to
PRODUCTION, builds the world with the refbox's field (the ground truth its
MachineInfo carries after the exploration period) and serves its cyan
stations on the broker, reports the machines, and then plays
the robot's hand in the world: it puts workpieces on inputs and slides and
takes products off outputs while the refbox prepares each station type
(PrepareMachine on the encrypted team channel).  For each step it prints the
machine states the refbox announced (MachineInfo), the seconds from the
prepare to READY-AT-OUTPUT (or to the delivery/store being done) and what
the world shows, and exits 0 only when every step went as the refbox's
rules want.  Durations are the Festo ones (``--speed`` scales them).
"""
from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
import threading
import time

TEAM, KEY = "Carologistics", "randomkey"
CYAN_STATIONS = ("C-BS", "C-CS1", "C-CS2", "C-RS1", "C-RS2", "C-DS", "C-SS")
TYPES = {"BS": "BS", "CS1": "CS", "CS2": "CS", "RS1": "RS", "RS2": "RS", "DS": "DS", "SS": "SS"}


def custom_cfg(broker_port: int, exploration_time: int, port_offset: int = 0,
               opcua_ports: dict[str, int] | None = None) -> str:
    lines = ["%YAML 1.2", "%TAG ! tag:fawkesrobotics.org,cfg/", "---", "# rll-bt check", "---",
             "llsfrb:", "  game:", f"    teams: [{TEAM}]", "    crypto-keys:", f"      {TEAM}: {KEY}",
             "    random-machine-down-times: false", f"    exploration-time: {exploration_time}",
             "  mps:", "    stations:"]
    for name in CYAN_STATIONS:
        lines += [f"      {name}:", "        active: true", f"        type: {TYPES[name[2:]]}",
                  f"        connection: {'plc' if opcua_ports else 'mqtt'}", "        host: 127.0.0.1",
                  f"        port: !tcp-port {opcua_ports[name] if opcua_ports else broker_port}"]
    return "\n".join(lines) + "\n" + comm_cfg(port_offset)


def comm_cfg(offset: int) -> str:
    """``llsfrb/comm`` keys moving every refbox port by ``offset`` (0: the defaults), so a
    check can run beside another refbox on the same machine."""
    if not offset:
        return ""
    text = f"  comm:\n    server-port: !tcp-port {4444 + offset}\n"
    for peer, send, recv in (("public", 4444, 4445), ("cyan", 4441, 4446), ("magenta", 4442, 4447)):
        text += (f"    {peer}-peer: {{host: !ipv4 127.0.0.1, send-port: !udp-port {send + offset}, "
                 f"recv-port: !udp-port {recv + offset}}}\n")
    return text


def main_cfg_args(refbox: str, run_dir: str, offset: int) -> list[str]:
    """``--cfg-main FILE`` moving the websocket port by ``offset`` (the refbox takes
    that port from its main config only, not from --cfg-custom)."""
    if not offset:
        return []
    src = os.path.join(os.path.dirname(os.path.realpath(refbox)), "..", "cfg", "main", "default_main.yaml")
    with open(src) as f:
        text = f.read()
    dst = os.path.join(run_dir, "main.yaml")
    with open(dst, "w") as f:
        f.write(text.replace("port: 1234", f"port: {1234 + offset}"))
    return ["--cfg-main", dst]


def port_free(port: int) -> bool:
    import socket
    with socket.socket() as s:
        return s.connect_ex(("127.0.0.1", port)) != 0


class WorldThread:
    """The world stepped on the wall clock; ``call`` runs a function on its thread."""

    def __init__(self, world, hall, dt=0.02):
        self.world, self.hall, self.dt = world, hall, dt
        self._calls, self._lock, self._stop = [], threading.Lock(), threading.Event()
        self._thread = threading.Thread(target=self._loop, daemon=True)
        self._thread.start()

    def _loop(self):
        t0, w0 = time.monotonic(), self.world.time
        while not self._stop.is_set():
            with self._lock:
                calls, self._calls = self._calls, []
            for fn, box, done in calls:
                try:
                    box.append(fn())
                except Exception as e:
                    box.append(e)
                done.set()
            self.hall.update()
            ahead = (self.world.time - w0) - (time.monotonic() - t0)
            if ahead > 0:
                time.sleep(ahead)
            self.world.step(self.dt)

    def call(self, fn):
        box, done = [], threading.Event()
        with self._lock:
            self._calls.append((fn, box, done))
        done.wait(10)
        if isinstance(box[0], Exception):
            raise box[0]
        return box[0]

    def stop(self):
        self._stop.set()
        self._thread.join(5)


class Team:
    """The team's side of the refbox: control over TCP 4444, reports and
    prepares on the cyan channel, MachineInfo states collected."""

    def __init__(self, host="127.0.0.1", offset=0):
        from rll_bt import msgs
        from rll_bt.comm import MessageRegistry, StreamClient, UdpPeer
        self.ms = msgs.message_set("rcll2025")
        reg = MessageRegistry.from_message_set(self.ms)
        self.ctl = StreamClient(host, 4444 + offset, registry=reg, channel="control")
        self.peer = UdpPeer(host, 4446 + offset, 4441 + offset, registry=reg, channel="team", key=KEY)
        self.states: dict[str, list[tuple[float, str]]] = {}
        self.points = 0
        self.field: dict[str, tuple[str, int]] = {}
        self.last_info = None
        self._stop = threading.Event()
        self._t = threading.Thread(target=self._listen, daemon=True)
        self._t.start()

    def _listen(self):
        while not self._stop.is_set():
            self.peer.wait(0.1)
            for r in self.peer.receive():
                if r.type_name.endswith("MachineInfo"):
                    self.last_info = r.msg
                    for m in r.msg.machines:
                        if m.HasField("zone"):
                            self.field[m.name] = (self.ms.enum("Zone").Name(m.zone), m.rotation)
                        seq = self.states.setdefault(m.name, [])
                        if not seq or seq[-1][1] != m.state:
                            seq.append((time.monotonic(), m.state))
            self.ctl.wait(0.0)
            for r in self.ctl.receive():
                if r.type_name.endswith("GameState"):
                    self.points = r.msg.points_cyan

    def control(self, name, **fields):
        msg = self.ms.get(name)(**fields)
        assert self.ctl.wait_connected(20), "refbox TCP 4444 not reachable"
        assert self.ctl.send(msg), f"{name} not sent"

    def send(self, name, **fields):
        self.peer.send(self.ms.get(name)(**fields))

    def wait_state(self, machine, state, since, timeout=60.0):
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            for t, s in self.states.get(machine, []):
                if t >= since and s == state:
                    return t
            time.sleep(0.05)
        return None

    def close(self):
        self._stop.set()
        self._t.join(2)
        self.peer.close()
        self.ctl.close()


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--refbox", required=True, help="path of the refbox binary (bin/refbox)")
    ap.add_argument("--seed", type=int, default=1, help="world seed (default 1)")
    ap.add_argument("--wire", choices=("mqtt", "opcua"), default="mqtt",
                    help="the refbox's machine back-end: mqtt (through a broker) or opcua (connection: plc, "
                         "needs a refbox built with freeopcua); default mqtt")
    ap.add_argument("--speed", type=float, default=1.0, help="station durations times this (default 1)")
    ap.add_argument("--port-offset", type=int, default=0,
                    help="move every refbox port by N (TCP 4444+N ...), to run beside another refbox")
    ap.add_argument("--response-delay", type=float, default=None, metavar="MS",
                    help="OPC-UA: hold each write's response this long (default: the server's own)")
    args = ap.parse_args(argv)
    started = time.monotonic()
    from backends.sim import World
    from backends.sim.mps import Broker, Durations, MachineHall, MqttMachines
    from backends.sim.stored import StoredGame

    if not port_free(4444 + args.port_offset):
        print(f"TCP {4444 + args.port_offset} is taken (another refbox?): use --port-offset", file=sys.stderr)
        return 3
    run_dir = tempfile.mkdtemp(prefix="rll-bt-refbox-check-")
    broker = Broker("amqtt")
    world = hall = served = wt = None        # built once the refbox has told its field (MQTT)
    opcua_ports = None
    if args.wire == "opcua":
        # the refbox connects to every PLC at start and waits for it: the servers come first,
        # on a world of its own seed (the refbox's field is not known yet)
        from backends.sim.mps import OpcuaMachines
        from backends.sim.mps.opcua import default_ports
        opcua_ports = {m: p + args.port_offset for m, p in default_ports(CYAN_STATIONS).items()}
        world = World("rcll2025", seed=args.seed)
        hall = MachineHall(world, CYAN_STATIONS, durations=Durations().scaled(args.speed))
        delay = {} if args.response_delay is None else {"response_delay": args.response_delay / 1000.0}
        served = OpcuaMachines(hall, ports=opcua_ports, **delay,
                               progress=lambda line: print(line, file=sys.stderr)).start()
        args.response_delay = served.response_delay * 1000.0
        wt = WorldThread(world, hall)
    cfg = os.path.join(run_dir, "check.yaml")
    with open(cfg, "w") as f:
        f.write(custom_cfg(broker.port, exploration_time=5, port_offset=args.port_offset, opcua_ports=opcua_ports))
    out = open(os.path.join(run_dir, "refbox.out"), "w")  # noqa: SIM115 (closed below)
    command = [args.refbox, *main_cfg_args(args.refbox, run_dir, args.port_offset), "--cfg-custom", cfg]
    refbox = subprocess.Popen(command, cwd=run_dir, stdout=out,
                              stderr=subprocess.STDOUT)
    print(f"refbox pid {refbox.pid}, logs in {run_dir}", file=sys.stderr)
    team = None
    results = []
    try:
        team = Team(offset=args.port_offset)
        time.sleep(8)
        # one at a time: RUNNING before the phase would start a training game
        for name, fields in (("SetTeamName", {"team_name": TEAM, "team_color": "CYAN"}),
                             ("SetGamePhase", {"phase": "SETUP"}), ("SetGameState", {"state": "RUNNING"})):
            team.control(name, **fields)
            time.sleep(0.5)
        # the field is generated in SETUP (the solver is checked only while the
        # previous phase is PRE_GAME); the refbox logs when it is done
        _wait_log(os.path.join(run_dir, "refbox.out"), "the machine generation is finished", 180)
        team.control("SetGamePhase", phase="PRODUCTION")
        field = _field(team)
        print("refbox field: " + ", ".join(f"{m} {z}/{r}" for m, (z, r) in sorted(field.items())),
              file=sys.stderr)
        entries = [{"name": m, "type": TYPES[m[2:]], "zone": z, "rotation": r}
                   for m, (z, r) in field.items() if m.startswith("C-")]
        # the world takes the refbox's field: its stations where the refbox placed its machines
        # (only the broker had to be up when the refbox started; the stations connect now)
        if world is None:
            game = StoredGame.from_machine_info(team.last_info)
            world = World("rcll2025", seed=args.seed, layout=game.layout())
            hall = MachineHall(world, CYAN_STATIONS, durations=Durations().scaled(args.speed),
                               feeders=dict(game.ring_colors))
            served = MqttMachines(hall, broker.host, broker.port).start()
            wt = WorldThread(world, hall)
        placed = {m: (world.profile.zone_name(world.station(m).zone), world.station(m).rotation)
                  for m in CYAN_STATIONS}
        if args.wire == "mqtt":
            results.append(("world field = refbox field", placed == {m: field[m] for m in CYAN_STATIONS}, 0.0,
                            ", ".join(f"{m} {z}/{r}" for m, (z, r) in sorted(placed.items()))))
        for _ in range(3):
            team.send("MachineReport", team_color="CYAN", machines=entries)
            time.sleep(1)
        results += _play(team, wt, world, hall)
    finally:
        if team:
            team.close()
        refbox.terminate()
        try:
            refbox.wait(10)
        except subprocess.TimeoutExpired:
            refbox.kill()
        out.close()
        if wt:
            wt.stop()
        if served:
            served.stop()
        broker.stop()
        if world:
            world.close()
    print(f"\n{'step':34} {'ok':3} {'s':>6}  refbox states / world")
    for step, ok, secs, text in results:
        print(f"{step:34} {'yes' if ok else 'NO':3} {secs:6.1f}  {text}")
    print(f"cyan points: {team.points if team else '?'}; {args.wire} refusals: "
          f"{len(served.errors) if served else '?'}")
    if args.wire == "opcua":
        minutes = (time.monotonic() - started) / 60.0
        timeouts = _timeouts(run_dir)
        print(f"refbox OPC-UA client: {sum(timeouts.values())} requests timed out in {minutes:.1f} min "
              f"({', '.join(f'{m} {n}' for m, n in sorted(timeouts.items())) or 'none'}; "
              f"server response delay {args.response_delay:g} ms)")
    return 0 if results and all(ok for _, ok, _, _ in results) else 1


def _timeouts(run_dir: str) -> dict[str, int]:
    """Per station: how often the refbox's OPC-UA client logged a request timed out
    (``mps/<NAME>.log`` in its run directory)."""
    out = {}
    mps = os.path.join(run_dir, "mps")
    for name in sorted(os.listdir(mps)) if os.path.isdir(mps) else ():
        with open(os.path.join(mps, name), errors="replace") as f:
            n = f.read().count("timed out")
        if n:
            out[name.rsplit(".", 1)[0]] = n
    return out


def _wait_log(path: str, text: str, timeout: float) -> None:
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        with open(path, errors="replace") as f:
            if text in f.read():
                return
        time.sleep(0.5)
    raise RuntimeError(f"the refbox did not log {text!r} within {timeout:.0f} s")


def _field(team, timeout=180.0) -> dict[str, tuple[str, int]]:
    """Where the refbox placed the cyan machines: its MachineInfo carries the
    ground truth once the exploration period is over."""
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if len(team.field) >= 7:
            return dict(team.field)
        time.sleep(0.5)
    raise RuntimeError(f"the refbox sent no field (MachineInfo zones: {team.field})")


def _play(team, wt, world, hall):
    results = []

    def step(label, machine, final, prepare, before=None, after_ready=None, check=None, timeout=60):
        if before:
            wt.call(before)
        t0 = time.monotonic()
        team.send("PrepareMachine", team_color="CYAN", machine=machine, **prepare)
        t = team.wait_state(machine, final, t0, timeout)
        ok = t is not None
        result = wt.call(check) if check and ok else ""
        if ok and after_ready:
            wt.call(after_ready)
        idle = team.wait_state(machine, "IDLE", (t or t0) + 0.01, 30) if ok else None
        seen = [s for tt, s in team.states.get(machine, []) if tt >= t0]
        ok = ok and idle is not None and (not check or bool(result))
        results.append((label, ok, (t - t0) if t else float("nan"), f"{'>'.join(seen)} | {result}"))
        print(results[-1], file=sys.stderr)

    take = lambda m, s: (lambda: world.remove_workpiece(m, s))            # noqa: E731
    put = lambda m, s, *a, **k: (lambda: world.spawn_workpiece(m, s, *a, **k))   # noqa: E731
    def output(machine, describe):
        """A check: the workpiece at ``machine``'s output described, or "" when there is none."""
        def check():
            wp = world.workpiece_at(machine, "output")
            return describe(wp) if wp else ""
        return check

    step("BS dispense BASE_RED to output", "C-BS", "READY-AT-OUTPUT",
         {"instruction_bs": {"side": "OUTPUT", "color": "BASE_RED"}},
         after_ready=take("C-BS", "output"),
         check=output("C-BS", lambda wp: f"output {wp.base}"))
    step("CS1 retrieve cap", "C-CS1", "READY-AT-OUTPUT",
         {"instruction_cs": {"operation": "RETRIEVE_CAP"}},
         before=put("C-CS1", "input", "BASE_BLACK", cap="CAP_BLACK"),
         after_ready=take("C-CS1", "output"),
         check=lambda: hall["C-CS1"].cap_buffer)
    step("CS1 mount cap", "C-CS1", "READY-AT-OUTPUT",
         {"instruction_cs": {"operation": "MOUNT_CAP"}},
         before=put("C-CS1", "input", "BASE_RED"), after_ready=take("C-CS1", "output"),
         check=output("C-CS1", lambda wp: wp.cap and f"output {wp.base}+{wp.cap}"))
    for _ in range(2):
        wt.call(put("C-RS1", "slide", "BASE_RED"))
        time.sleep(0.5)
    step("RS1 mount RING_ORANGE (feeder 1)", "C-RS1", "READY-AT-OUTPUT",
         {"instruction_rs": {"ring_color": "RING_ORANGE"}},
         before=put("C-RS1", "input", "BASE_SILVER"), after_ready=take("C-RS1", "output"),
         check=output("C-RS1", lambda wp: wp.rings and f"output rings {wp.rings}"))
    step("DS deliver (order 0, consume)", "C-DS", "WAIT-IDLE",
         {"instruction_ds": {"order_id": 0}},
         before=put("C-DS", "input", "BASE_RED", cap="CAP_BLACK"),
         check=lambda: hall["C-DS"].delivered and f"delivered to slot {hall['C-DS'].delivered[-1].data['slot']}")
    step("SS retrieve shelf 0 slot 1", "C-SS", "READY-AT-OUTPUT",
         {"instruction_ss": {"operation": "RETRIEVE", "shelf": 0, "slot": 1}},
         after_ready=take("C-SS", "output"),
         check=lambda: "retrieved" if any("retrieved" in r.text for r in hall["C-SS"].records) else "")
    return results


if __name__ == "__main__":
    sys.exit(main())
