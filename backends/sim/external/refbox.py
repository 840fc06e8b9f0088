"""The PyBullet world's game against a refbox elsewhere (``rll-bt sim --refbox external``).

:func:`open_external` is the simulator factory's ``refbox="external"``:
the refbox runs already (the real one, or ``rll-bt refbox sim``), its
stations configured for the world's machines (MQTT through a broker, or
OPC-UA PLCs), its clock following SimTimeSync.  In order:

1. connect to its controller stream (``host``:``port``, TCP 4444 by
   default) and send SimTimeSync from then on (the wall clock's time until
   the world exists, then the world's, continuing);
2. as the operator (``control="auto"``): name the team (SetTeamName cyan),
   SETUP, RUNNING, half a second apart (RUNNING before SETUP would start a
   training game; the real refbox generates its field only in a SETUP
   entered from PRE_GAME, and times that out in *game* time, so the clock
   runs at real time meanwhile); ``control="manual"``: a person does this;
3. wait for the field: MachineInfo on the stream gives every machine's zone
   and rotation once it is generated;
4. build the world on that field, each ring station's feeders holding the
   refbox's colours, the cap stations' shelves kept filled with carriers,
   and serve the stations: over MQTT to the broker (``stations="mqtt"``),
   or as OPC-UA PLCs (``"opcua"``, already serving since step 1: the
   refbox connects to its PLCs when it starts, see :class:`HeldHall`).

:class:`ExternalRefbox` is then the game's refbox: ``start()`` (the
robots are up) switches SETUP to the next phase (``control="auto"``),
``step()`` after each world step reads the stream, advances the machines,
and sends the world's time; ``pause(True)`` sends it as paused (the world
is held).  The view (status, points, deliveries, orders) is what the
stream said (:class:`.link.ControllerLink`).
"""
from __future__ import annotations

import sys
import time

from rll_bt.contracts import SimulatedRefbox, StationTruth
from rll_bt.errors import Unavailable, UserError
from rll_bt.rules import machine_type

from .link import ControllerLink

CONTROLS = ("auto", "manual")
STATIONS = ("mqtt", "opcua")
#: the cap carriers on each cap station's shelf (the 2017+ rules' caps)
CARRIERS = {"CS1": "CAP_GREY", "CS2": "CAP_BLACK"}
NEXT_PHASE = {"rcll2016": "EXPLORATION", "rcll2025": "PRODUCTION"}


def _say(text: str) -> None:
    print(f"external refbox: {text}", file=sys.stderr, flush=True)


class HeldHall:
    """A machine hall before its world exists: what the OPC-UA front end
    needs of a :class:`~backends.sim.mps.MachineHall` (names, kinds,
    listeners, an inbox), commands held until :meth:`bind` gives the real
    hall (they are handed over then, in order)."""

    def __init__(self, machines):
        self._kinds = {m: machine_type(m) for m in machines}
        self.machines = dict.fromkeys(self._kinds)
        self._held: list = []
        self._listeners: list = []
        self.hall = None

    def __getitem__(self, name: str):
        if self.hall is not None:
            return self.hall[name]
        return type("Held", (), {"kind": self._kinds[name]})()

    def add_listener(self, fn) -> None:
        self._listeners.append(fn)
        if self.hall is not None:
            self.hall.add_listener(fn)

    def remove_listener(self, fn) -> None:
        self._listeners.remove(fn)
        if self.hall is not None:
            self.hall.remove_listener(fn)

    def submit(self, machine: str, command) -> None:
        if self.hall is None:
            self._held.append((machine, command))
        else:
            self.hall.submit(machine, command)

    def bind(self, hall) -> None:
        self.hall = hall
        for fn in self._listeners:
            hall.add_listener(fn)
        for machine, command in self._held:
            hall.submit(machine, command)
        self._held.clear()


class ExternalRefbox(SimulatedRefbox):
    """See the module doc; made by :func:`open_external`."""

    def __init__(self, link: ControllerLink, timesync, *, profile, team_name: str, control: str):
        self.link, self.timesync = link, timesync
        self.profile, self.team_name, self.control = profile, team_name, control
        self.world = None
        self.hall = None
        self.front_ends: list = []
        self._wall0 = time.monotonic()
        self._origin = 0.0            # SimTimeSync time when the world's clock was 0
        self._paused = False

    # -- time ---------------------------------------------------------------------------
    def sim_time(self) -> float:
        if self.world is None:
            return time.monotonic() - self._wall0
        return self._origin + self.world.clock.now()

    def adopt(self, world, hall) -> None:
        """The world exists: its clock continues the time sent so far."""
        self._origin = time.monotonic() - self._wall0 - world.clock.now()
        self.world, self.hall = world, hall

    def pause(self, paused: bool) -> None:
        """The world is held (True) or runs again: sent at once."""
        self._paused = bool(paused)
        self.timesync.update(self.sim_time(), paused=self._paused)

    # -- SimulatedRefbox --------------------------------------------------------------------
    def start(self) -> None:
        st = self.status()
        if self.control == "auto" and st.phase == "SETUP":
            self.link.send("SetGamePhase", phase=NEXT_PHASE.get(self.profile.name, "PRODUCTION"))
            _say(f"the robots are up: {NEXT_PHASE.get(self.profile.name)} (after {st.game_time:.0f} s of SETUP)")

    def step(self) -> None:
        self.link.poll()
        if self.hall is not None:
            self.hall.update()
        self.timesync.update(self.sim_time(), paused=self._paused)

    def status(self):
        return self.link.status()

    def awards(self):
        return self.link.awards()

    def deliveries(self):
        return self.link.deliveries()

    def orders(self) -> list[dict]:
        return self.link.orders()

    def stations(self) -> dict[str, StationTruth]:
        states, w = self.link.machine_states(), self.world.pybullet
        return {name: StationTruth(name, w.station(name).team, int(w.station(name).zone),
                                   int(w.station(name).rotation), w.station(name).pose,
                                   states.get(name, "IDLE"))
                for name in w.machines}

    def close(self) -> None:
        for fe in reversed(self.front_ends):
            try:
                fe.stop()
            except Exception:
                pass
        self.front_ends.clear()
        self.timesync.close()
        self.link.close()


def _operate(link: ControllerLink, refbox: ExternalRefbox, team: str, control: str, timeout: float) -> None:
    """Step 2 of the module doc: name the team, SETUP, RUNNING (auto), the clock running."""
    deadline = time.monotonic() + timeout
    while link.game_state is None:
        refbox.step()
        if time.monotonic() > deadline:
            raise Unavailable(f"the refbox at {link.address} sends no GameState", where="--refbox-host")
        time.sleep(0.05)
    st = link.status()
    if control != "auto":
        _say(f"manual control: waiting for its field (now {st.phase} {st.state})")
        return
    if st.phase != "PRE_GAME":
        _say(f"it is in {st.phase} {st.state} already: taking its game as it is")
        return
    gs = link.game_state
    for name, fields in (("SetTeamName", {"team_name": team, "team_color": "CYAN"}),
                         ("SetGamePhase", {"phase": "SETUP"}), ("SetGameState", {"state": "RUNNING"})):
        link.send(name, **fields)
        end = time.monotonic() + 0.5
        while time.monotonic() < end:
            refbox.step()
            time.sleep(0.02)
    while link.status().phase == "PRE_GAME":      # until its GameState says it took SETUP (a loaded
        refbox.step()                              # machine may hear it after the field's MachineInfo)
        if time.monotonic() > deadline:
            raise Unavailable(f"the refbox at {link.address} stays in PRE_GAME after SetGamePhase SETUP",
                              where="--refbox-host")
        time.sleep(0.05)
    gs = link.game_state
    if gs is not None and gs.team_cyan != team:
        raise UserError(f"the refbox did not take the team name {team!r} (cyan is {gs.team_cyan!r})",
                        where="--team", hint="the refbox's llsfrb/game/teams must list it, with its key")
    _say(f"team {team} named, SETUP, RUNNING")


def _wait_field(link: ControllerLink, refbox: ExternalRefbox, machines, timeout: float):
    deadline = time.monotonic() + timeout
    while True:
        refbox.step()
        field = link.field(machines)
        if field is not None:
            return field
        if time.monotonic() > deadline:
            raise Unavailable(f"the refbox at {link.address} announced no field within {timeout:.0f} s "
                              f"(zones of {sum(1 for m in link.machines.values() if m.zone)} machines)",
                              hint="it generates its field in a SETUP entered from PRE_GAME, on a clock that runs")
        time.sleep(0.05)


def open_external(world_factory, profile, *, team_name: str, host: str = "127.0.0.1", port: int = 4444,
                  control: str = "auto", stations: str = "mqtt", broker: str | None = None,
                  opcua_host: str = "127.0.0.1", opcua_base_port: int = 4840, timeout: float = 180.0,
                  transport=None):
    """Steps 1-4 of the module doc: (world, :class:`ExternalRefbox`).
    ``world_factory(layout)`` builds the world on the refbox's field;
    ``broker``: "HOST:PORT" (default the refbox host's 1883)."""
    from rll_bt.comm.jsonlink import parse_address

    from ..mps import MachineHall, MqttMachines, OpcuaMachines, Product
    from ..mps.timesync import TimeSync
    if control not in CONTROLS:
        raise UserError(f"must be one of {', '.join(CONTROLS)}, not {control!r}", where="--refbox-control")
    if stations not in STATIONS:
        raise UserError(f"must be one of {', '.join(STATIONS)}, not {stations!r}", where="--stations")
    machines = list(profile.machines())
    held = None
    early = []
    if stations == "opcua":        # the refbox connects to its PLCs at its start: serve before it is up
        held = HeldHall(machines)
        early.append(OpcuaMachines(held, opcua_host, base_port=opcua_base_port,
                                   progress=lambda line: _say(line)).start())
    link = ControllerLink(host, port, profile.name, transport=transport)
    try:
        _say(f"waiting for the refbox at {host}:{port}")
        if not link.wait_connected(timeout):
            raise Unavailable(f"cannot reach the refbox's controller stream at {host}:{port}",
                              where="--refbox-host", hint="start the refbox first (docs/league.md)")
        sync = TimeSync(profile=profile.name, transport=link.stream)
        refbox = ExternalRefbox(link, sync, profile=profile, team_name=team_name, control=control)
        refbox.front_ends += early
        _operate(link, refbox, team_name, control, timeout)
        field = _wait_field(link, refbox, machines, timeout)
        _say("its field: " + ", ".join(f"{m} {z}/{r}" for m, (z, r) in sorted(field.machines.items())))
        world = world_factory(field.layout())
        shelves = {m: Product("BASE_RED", (), CARRIERS[m[2:]]) for m in machines if m[2:] in CARRIERS}
        hall = MachineHall(world.pybullet, feeders=dict(field.ring_colors), shelves=shelves)
        refbox.adopt(world, hall)
        if held is not None:
            held.bind(hall)
        else:
            b_host, b_port = parse_address(broker or f"{host}:1883", "the broker's address")
            try:
                refbox.front_ends.append(MqttMachines(hall, b_host, b_port).start())
            except ConnectionError as exc:
                world.close()
                raise Unavailable(str(exc), where="--mqtt") from None
            _say(f"the world's stations on MQTT through {b_host}:{b_port}")
        return world, refbox
    except BaseException:
        for fe in early:
            fe.stop()
        link.close()
        raise


__all__ = ["CONTROLS", "STATIONS", "ExternalRefbox", "HeldHall", "open_external"]
