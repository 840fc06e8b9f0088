"""The simulated refbox driving MQTT machines, as the real refbox does with
``connection: mqtt`` (``reference/refbox-mqtt.md``; the other side of
:mod:`backends.sim.mps.mqtt`).

The refbox's game keeps its own picture of the stations, as the real
refbox keeps its facts: :class:`MachineWorld` is a
:class:`~.world.RefboxWorld` over an in-memory :class:`~.world.TableWorld`
(the stations' slots as the refbox believes them) that commands the real
machines over MQTT and turns what they report into the slot events the
game reacts to.  Nothing else crosses: the machines are wherever the broker
reaches (``rll-bt sim --refbox external`` serves the PyBullet world's).

Commands (``MPS/<NAME>/Command``, QoS 2), at the station's transitions
(the refbox's production.clp):

- PREPARED: a ring or cap station, or a storage station told to STORE,
  ``MOVE_CONVEYOR TO_OUTPUT MID`` (the belt waits for the workpiece);
- PROCESSING: BS ``GET_BASE <colour>`` then the belt to the instructed
  side; RS ``MOUNT_RING RING<feeder>`` (the feeder holding the colour),
  CS ``CAP_ACTION RETRIEVE|MOUNT``, SS ``RETRIEVE s,l``, each followed by
  ``MOVE_CONVEYOR TO_OUTPUT OUT``; SS ``STORE s,l``; DS ``DELIVER SLOT<gate>``;
- BROKEN: ``RESET``;
- the lights: ``LIGHT <colour> <state>`` for each light that changed.

Feedback (``Status``, ``WP-Sensor``, ``Barcode``, ``SlideCount``):

- a Barcode on an RS, CS, DS or SS input is a workpiece put there (a robot's
  doing): the game hears a ``put`` on the input;  on a BS, or an SS
  retrieving, it names the workpiece the machine is making;
- the workpiece sensor falling while the station holds a product at its
  output (or the BS's input side) is the product taken: a ``take``;
- each SlideCount step is a base on a ring station's slide.

What a workpiece is (base, rings, cap) is what the refbox made of it: the
barcode of a base it dispensed, or of a workpiece it worked on, keeps the
description the refbox gave its product; an unknown one is a cap carrier
at a cap station not told to mount a cap (the shelves are the field's, not
the refbox's), a bare base elsewhere.  The game's processing times must cover the machines' (the
refbox hands a product over when its time is up): :func:`machine_config`
gives them from the machines' :class:`~backends.sim.mps.Durations`.
"""
from __future__ import annotations

import logging
import queue
import threading
from dataclasses import replace

from rll_bt.rules import machine_type
from rll_bt.rules.machines import MachineTimes

from . import events as E
from .stations import StationConfig
from .world import INPUT, OUTPUT, SLIDE, TableWorld, Workpiece

log = logging.getLogger(__name__)

PREFIX = "MPS"
QOS = 2
FEEDBACK = ("Status", "WP-Sensor", "Barcode", "SlideCount")
#: game seconds added to each machine time (the feedback's way through the broker)
MARGIN = 0.5


def machine_config(durations=None, margin: float = MARGIN, base: StationConfig | None = None) -> StationConfig:
    """Station times that cover the machines' steps: the machines' own durations
    (:class:`~backends.sim.mps.Durations`), each operation ``margin`` s longer
    (its feedback's way through the broker)."""
    from backends.sim.mps.machine import Durations
    d = durations or Durations()
    base = base or StationConfig()
    times = MachineTimes(base_dispense=d.base_dispense + margin, belt_to_middle=d.belt_in_to_mid,
                         belt_to_output=d.belt_mid_to_out + margin, ring_mount=d.ring + margin,
                         cap_operation=d.cap + margin, storage_operation=d.storage + margin,
                         delivery_slots=tuple(t + margin for t in d.deliver), minimum=d.min_operation)
    return replace(base, times=times)


class MachineWorld:
    """The stations of ``layout`` as MQTT machines behind the broker at
    ``host``:``port``.  Call :meth:`attach` with the game, then :meth:`pump`
    in the refbox's loop (it sends what the game's new transitions call for
    and delivers what the machines reported); :meth:`close` at the end.
    ``sent`` lists (machine, payload) published, ``heard`` (machine, topic
    leaf, payload) received."""

    robots: tuple = ()                 # no robots of its own (the mockup stays off)

    def __init__(self, layout, host: str = "127.0.0.1", port: int = 1883, *, client_id: str = "Refbox_sim",
                 timeout: float = 10.0):
        import paho.mqtt.client as paho
        self.layout = layout
        self.address = f"{host}:{port}"
        self.table = TableWorld(layout)
        self.game = None
        self.sent: list[tuple[str, str]] = []
        self.heard: list[tuple[str, str, str]] = []
        self._inbox: queue.SimpleQueue = queue.SimpleQueue()
        self._lights: dict[str, dict[str, str]] = {}
        self._wp: dict[int, Workpiece] = {}                # barcode -> what the refbox made of it
        self._making: dict[str, int] = {}                  # BS/SS: barcode of the product in the making
        self._at_input: dict[str, int] = {}                # barcode of what lies on a station's input
        self._sensor: dict[str, bool] = {}
        self._slide: dict[str, int] = {}
        self._events = 0
        self._connected = threading.Event()
        self._client = paho.Client(paho.CallbackAPIVersion.VERSION2, client_id=client_id,
                                   protocol=paho.MQTTv311)
        self._client.on_connect = self._on_connect
        self._client.on_message = self._on_message
        try:
            self._client.connect(host, int(port))
        except OSError as exc:
            raise ConnectionError(f"cannot reach the MQTT broker at {host}:{port}: {exc}") from None
        self._client.loop_start()
        if not self._connected.wait(timeout):
            self.close()
            raise ConnectionError(f"the MQTT broker at {host}:{port} did not accept the refbox in {timeout:g} s")

    # -- MQTT (paho's thread) ----------------------------------------------------------
    def _on_connect(self, client, userdata, flags, reason, properties=None) -> None:
        client.subscribe([(f"{PREFIX}/+/{leaf}", QOS) for leaf in FEEDBACK])
        self._connected.set()

    def _on_message(self, client, userdata, msg) -> None:
        parts = msg.topic.split("/")
        if len(parts) == 3 and parts[0] == PREFIX and parts[2] in FEEDBACK:
            self._inbox.put((parts[1], parts[2], msg.payload.decode("ascii", errors="replace")))

    def _publish(self, machine: str, payload: str) -> None:
        self.sent.append((machine, payload))
        self._client.publish(f"{PREFIX}/{machine}/Command", payload, qos=QOS)

    # -- RefboxWorld: the refbox's picture ------------------------------------------------
    def set_lights(self, machine: str, *, red: str = "OFF", yellow: str = "OFF", green: str = "OFF") -> None:
        self.table.set_lights(machine, red=red, yellow=yellow, green=green)
        want = {"RED": red, "YELLOW": yellow, "GREEN": green}
        shown = self._lights.get(machine)
        for colour, state in want.items():
            if shown is None or shown[colour] != state:
                self._publish(machine, f"LIGHT {colour} {state}")
        self._lights[machine] = want

    def lights(self, machine: str) -> dict[str, str]:
        return self.table.lights(machine)

    def spawn_workpiece(self, machine: str, slot: str, base: str, rings=(), cap=None) -> Workpiece:
        wp = self.table.spawn_workpiece(machine, slot, base, rings, cap)
        if slot in (INPUT, OUTPUT):                          # a product the station made
            code = self._making.pop(machine, None) if machine_type(machine) in ("BS", "SS") \
                else self._at_input.pop(machine, None)
            if code is not None:
                self._wp[code] = Workpiece(base, tuple(rings), cap)
        return wp

    def remove_workpiece(self, machine: str, slot: str, workpiece_id=None):
        return self.table.remove_workpiece(machine, slot, workpiece_id)

    def workpiece_at(self, machine: str, slot: str):
        return self.table.workpiece_at(machine, slot)

    def workpieces_at(self, machine: str, slot: str):
        return self.table.workpieces_at(machine, slot)

    def add_slot_listener(self, fn) -> None:
        self.table.add_slot_listener(fn)

    # -- the loop ----------------------------------------------------------------------------
    def attach(self, game) -> None:
        """Follow ``game``'s station transitions from now on."""
        self.game = game
        self._events = len(game.events)

    def pump(self) -> int:
        """Send the commands the game's transitions since the last call call for, then
        deliver what the machines reported; returns how many reports."""
        if self.game is not None:
            new = self.game.events[self._events:]
            self._events = len(self.game.events)
            for ev in new:
                if ev.kind == E.MACHINE and ev.machine in self.game.stations:
                    self._transition(self.game.stations[ev.machine], ev.data.get("state"))
        n = 0
        while True:
            try:
                machine, leaf, payload = self._inbox.get_nowait()
            except queue.Empty:
                return n
            n += 1
            self.heard.append((machine, leaf, payload))
            if machine in self.layout.machines:
                try:
                    self._feedback(machine, leaf, payload)
                except ValueError as exc:
                    log.warning("%s %s %r: %s", machine, leaf, payload, exc)

    def _transition(self, st, state: str | None) -> None:
        kind, ins, m = st.kind, st.instruction, st.name
        if state == "BROKEN":
            self._publish(m, "RESET")
        elif state == "PREPARED":
            if kind in ("RS", "CS") or (kind == "SS" and getattr(ins, "operation", "") == "STORE"):
                self._publish(m, "MOVE_CONVEYOR TO_OUTPUT MID")
        elif state == "PROCESSING" and ins is not None:
            for payload in self._operation(st, ins):
                self._publish(m, payload)

    def _operation(self, st, ins) -> list[str]:
        out = "MOVE_CONVEYOR TO_OUTPUT OUT"
        if st.kind == "BS":
            side = "MOVE_CONVEYOR TO_INPUT IN" if ins.side == "INPUT" else out
            return [f"GET_BASE {ins.color.replace('BASE_', '')}", side]
        if st.kind == "RS":
            colours = tuple(self.game.rs_colors(st.name))
            feeder = colours.index(ins.ring_color) + 1 if ins.ring_color in colours else 1
            return [f"MOUNT_RING RING{feeder}", out]
        if st.kind == "CS":
            return [f"CAP_ACTION {'RETRIEVE' if ins.operation == 'RETRIEVE_CAP' else 'MOUNT'}", out]
        if st.kind == "DS":
            gate = int(self.game.rules.delivery_gate(self.game, ins) or 1)
            return [f"DELIVER SLOT{min(max(gate, 1), 3)}"]
        if st.kind == "SS" and ins.operation in ("RETRIEVE", "STORE"):
            cmd = f"{ins.operation} {ins.shelf},{ins.slot}"
            return [cmd, out] if ins.operation == "RETRIEVE" else [cmd]
        return []

    def _feedback(self, machine: str, leaf: str, payload: str) -> None:
        kind = machine_type(machine)
        if leaf == "Barcode":
            code = int(payload)
            st = self.game.stations.get(machine) if self.game is not None else None
            making = kind == "BS" or (kind == "SS" and st is not None
                                      and getattr(st.instruction, "operation", "") == "RETRIEVE")
            if making:
                self._making[machine] = code
                return
            self._at_input[machine] = code
            self._put(machine, INPUT, self._describe(machine, code, kind), code)
        elif leaf == "WP-Sensor":
            ready = payload == "WP"
            was = self._sensor.get(machine, False)
            self._sensor[machine] = ready
            if was and not ready:
                self._taken(machine)
        elif leaf == "SlideCount" and kind == "RS":
            count = int(payload)
            for _ in range(max(0, count - self._slide.get(machine, 0))):
                self.table.put(machine, SLIDE, Workpiece("BASE_RED"))
            self._slide[machine] = count

    def _describe(self, machine: str, code: int, kind: str) -> Workpiece:
        known = self._wp.get(code)
        if known is not None:
            return known
        cfg = self.game.config if self.game is not None else StationConfig()
        st = self.game.stations.get(machine) if self.game is not None else None
        if kind == "CS" and getattr(st.instruction if st else None, "operation", "") != "MOUNT_CAP":
            return Workpiece(cfg.carrier_base, (), cfg.cap_of(machine[2:]))    # a cap carrier from the shelf
        return Workpiece(cfg.carrier_base)

    def _put(self, machine: str, slot: str, wp: Workpiece, code: int) -> None:
        if self.table.workpiece_at(machine, slot) is not None:   # what the refbox still believed there
            self.table.remove_workpiece(machine, slot)
        self.table.put(machine, slot, replace(wp, id=code))

    def _taken(self, machine: str) -> None:
        st = self.game.stations.get(machine) if self.game is not None else None
        slot = getattr(st, "out_slot", OUTPUT) if st is not None else OUTPUT
        for where in (slot, OUTPUT, INPUT):
            if where in ("input", "output") and self._has_slot(machine, where) \
                    and self.table.workpiece_at(machine, where) is not None \
                    and (where != INPUT or machine_type(machine) == "BS"):
                self.table.take(machine, where)
                return

    @staticmethod
    def _has_slot(machine: str, slot: str) -> bool:
        from .world import station_slots
        return slot in station_slots(machine)

    def close(self) -> None:
        try:
            self._client.loop_stop()
            self._client.disconnect()
        except Exception:
            log.debug("closing the MQTT client failed", exc_info=True)


__all__ = ["MachineWorld", "machine_config"]
