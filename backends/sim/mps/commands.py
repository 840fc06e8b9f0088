"""The commands a referee box sends a station, in one form for both wires.

Over MQTT a command is an ASCII payload on ``MPS/<NAME>/Command``
(``reference/refbox-mqtt.md`` section 3): an action word and its arguments
separated by single spaces.  Over OPC-UA it is the Festo PLC's register
write: an action id (station type base 100..500 plus an operation, or a
"basic" id below 100 for lights, set-type and the heartbeat) and two 16-bit
data words.  :func:`parse_mqtt` and :func:`from_opcua` turn either into a
:class:`Command`; :meth:`Command.mqtt` and :meth:`Command.opcua` write it
back (for clients and logs).
"""
from __future__ import annotations

from dataclasses import dataclass

#: station type -> action id base of the PLC
TYPE_BASE = {"BS": 100, "RS": 200, "CS": 300, "DS": 400, "SS": 500}
#: station type -> payload of the PLC's set-type command
TYPE_CODE = {"BS": 1, "RS": 2, "CS": 3, "DS": 4, "SS": 5}
LIGHTS = ("RED", "YELLOW", "GREEN")
LIGHT_STATES = ("OFF", "ON", "BLINK")
LIGHT_IDS = {"RED": 21, "YELLOW": 22, "GREEN": 23}
LIGHT_RESET_ID = 20
SET_TYPE_ID = 10
#: base colour word -> PLC code (red 1, silver 2, black 3)
BASE_CODES = {"RED": 1, "SILVER": 2, "BLACK": 3}
SENSORS = {"IN": 1, "MID": 2, "OUT": 3}
DIRECTIONS = {"TO_OUTPUT": 1, "TO_INPUT": 2}
CAP_OPS = {"RETRIEVE": 1, "MOUNT": 2}
#: operation offsets added to the type base (the conveyor move is 2 on every type)
MOVE, GET_BASE, CAP_ACTION, MOUNT_RING, DELIVER = 2, 1, 1, 3, 1
SS_RETRIEVE, SS_STORE, SS_RELOCATE = 30, 40, 50
SHELVES, SHELF_SLOTS = 6, 8
#: ring colour enum number (as the refbox sends it in the second data word) -> name
RING_ENUM = {1: "RING_BLUE", 2: "RING_GREEN", 3: "RING_ORANGE", 4: "RING_YELLOW"}

#: actions that take time on the machine (the rest are instant)
STEPS = ("MOVE_CONVEYOR", "GET_BASE", "CAP_ACTION", "MOUNT_RING", "DELIVER", "RETRIEVE", "STORE",
         "RELOCATE")


class CommandError(ValueError):
    """A payload or register write that is no command of this station."""


@dataclass(frozen=True)
class Command:
    """``action`` and its typed ``args``:

    ``RESET`` (); ``LIGHT`` (colour, state) or ``LIGHT`` ("RESET",) for all
    off; ``MOVE_CONVEYOR`` (direction TO_OUTPUT|TO_INPUT, target
    IN|MID|OUT); ``GET_BASE`` (RED|BLACK|SILVER); ``CAP_ACTION``
    (RETRIEVE|MOUNT); ``MOUNT_RING`` (feeder 1|2, ring colour name or None);
    ``DELIVER`` (slot 1..3); ``RETRIEVE``/``STORE`` ((shelf, slot),);
    ``RELOCATE`` ((shelf, slot), (shelf, slot)); ``SET_TYPE`` (BS..SS,);
    ``NOTHING`` () (the PLC heartbeat)."""
    action: str
    args: tuple = ()

    @property
    def is_step(self) -> bool:
        return self.action in STEPS

    def mqtt(self) -> str:
        """The MQTT payload of this command."""
        a = self.action
        if a == "MOUNT_RING":
            return f"MOUNT_RING RING{self.args[0]}"
        if a == "DELIVER":
            return f"DELIVER SLOT{self.args[0]}"
        if a in ("RETRIEVE", "STORE", "RELOCATE"):
            return " ".join([a] + [f"{s},{lot}" for s, lot in self.args])
        if a in ("SET_TYPE", "NOTHING"):
            raise CommandError(f"{a} has no MQTT form")
        return " ".join([a, *map(str, self.args)])

    def opcua(self, station_type: str) -> tuple[str, int, int, int]:
        """(register "In" or "Basic", action id, data 0, data 1) of this command."""
        base = TYPE_BASE[station_type]
        a, args = self.action, self.args
        if a == "NOTHING":
            return "Basic", 0, 0, 0
        if a == "SET_TYPE":
            return "Basic", SET_TYPE_ID, TYPE_CODE[args[0]], 0
        if a == "LIGHT":
            if args[0] == "RESET":
                return "Basic", LIGHT_RESET_ID, 0, 0
            return "Basic", LIGHT_IDS[args[0]], LIGHT_STATES.index(args[1]), 0
        if a == "RESET":
            return "In", base, 0, 0
        if a == "MOVE_CONVEYOR":
            return "In", base + MOVE, SENSORS[args[1]], DIRECTIONS[args[0]]
        if a == "GET_BASE":
            return "In", base + GET_BASE, BASE_CODES[args[0]], 0
        if a == "CAP_ACTION":
            return "In", base + CAP_ACTION, CAP_OPS[args[0]], 0
        if a == "MOUNT_RING":
            colour = {v: k for k, v in RING_ENUM.items()}.get(args[1], 0)
            return "In", base + MOUNT_RING, args[0], colour
        if a == "DELIVER":
            return "In", base + DELIVER, args[0], 0
        if a in ("RETRIEVE", "STORE"):
            (shelf, slot), = args
            return "In", base + (SS_RETRIEVE if a == "RETRIEVE" else SS_STORE), shelf, slot
        if a == "RELOCATE":
            (s0, l0), (s1, l1) = args
            return "In", base + SS_RELOCATE, s0 * 10 + l0, s1 * 10 + l1
        raise CommandError(f"unknown action {a!r}")


def _word(words: list[str], i: int, choices, what: str) -> str:
    if i >= len(words) or words[i] not in choices:
        got = repr(words[i]) if i < len(words) else "nothing"
        raise CommandError(f"{what}: expected one of {', '.join(choices)}, got {got}")
    return words[i]


def _shelf_slot(text: str) -> tuple[int, int]:
    parts = text.split(",")
    if len(parts) != 2 or not all(p.isdigit() for p in parts):
        raise CommandError(f"expected <shelf>,<slot> (e.g. 0,1), got {text!r}")
    shelf, slot = int(parts[0]), int(parts[1])
    if shelf >= SHELVES or slot >= SHELF_SLOTS:
        raise CommandError(f"shelf {shelf} slot {slot} out of range (shelf 0..{SHELVES - 1}, "
                           f"slot 0..{SHELF_SLOTS - 1})")
    return shelf, slot


def parse_mqtt(payload: bytes | str) -> Command:
    """A ``Command`` payload as the refbox publishes it; CommandError otherwise."""
    if isinstance(payload, bytes):
        try:
            payload = payload.decode("ascii")
        except UnicodeDecodeError:
            raise CommandError(f"command payload is not ASCII: {payload[:40]!r}") from None
    words = payload.split(" ")
    action, n = words[0], len(words)
    expect = {"RESET": 1, "LIGHT": 3, "MOVE_CONVEYOR": 3, "GET_BASE": 2, "CAP_ACTION": 2,
              "MOUNT_RING": 2, "DELIVER": 2, "RETRIEVE": 2, "STORE": 2, "RELOCATE": 3}
    if action not in expect:
        raise CommandError(f"unknown command {payload[:40]!r} (known: {', '.join(expect)})")
    if action == "LIGHT" and n == 2 and words[1] == "RESET":
        return Command("LIGHT", ("RESET",))
    if n != expect[action]:
        raise CommandError(f"{action} takes {expect[action] - 1} argument(s): {payload[:60]!r}")
    if action == "RESET":
        return Command("RESET")
    if action == "LIGHT":
        return Command("LIGHT", (_word(words, 1, LIGHTS, "LIGHT colour"),
                                 _word(words, 2, LIGHT_STATES, "LIGHT state")))
    if action == "MOVE_CONVEYOR":
        return Command(action, (_word(words, 1, tuple(DIRECTIONS), "MOVE_CONVEYOR direction"),
                                _word(words, 2, tuple(SENSORS), "MOVE_CONVEYOR target")))
    if action == "GET_BASE":
        return Command(action, (_word(words, 1, tuple(BASE_CODES), "GET_BASE colour"),))
    if action == "CAP_ACTION":
        return Command(action, (_word(words, 1, tuple(CAP_OPS), "CAP_ACTION operation"),))
    if action == "MOUNT_RING":
        feeder = _word(words, 1, ("RING1", "RING2"), "MOUNT_RING feeder")
        return Command(action, (int(feeder[-1]), None))
    if action == "DELIVER":
        slot = _word(words, 1, ("SLOT1", "SLOT2", "SLOT3"), "DELIVER slot")
        return Command(action, (int(slot[-1]),))
    return Command(action, tuple(_shelf_slot(w) for w in words[1:]))


def from_opcua(station_type: str, action_id: int, data0: int, data1: int) -> Command:
    """The command a PLC register write (action id and data words) means for
    a station of ``station_type``; CommandError for an unknown id."""
    if action_id == 0:
        return Command("NOTHING")
    if action_id == SET_TYPE_ID:
        for kind, code in TYPE_CODE.items():
            if code == data0:
                return Command("SET_TYPE", (kind,))
        raise CommandError(f"set-type with unknown station type code {data0}")
    if action_id == LIGHT_RESET_ID:
        return Command("LIGHT", ("RESET",))
    for colour, lid in LIGHT_IDS.items():
        if action_id == lid:
            if not 0 <= data0 < len(LIGHT_STATES):
                raise CommandError(f"light {colour} with unknown state {data0}")
            return Command("LIGHT", (colour, LIGHT_STATES[data0]))
    base = TYPE_BASE[station_type]
    op = action_id - base
    if not 0 <= op < 100:
        raise CommandError(f"action id {action_id} is not for a {station_type} (base {base})")
    if op == 0:
        return Command("RESET")
    if op == MOVE:
        sensor = {v: k for k, v in SENSORS.items()}.get(data0)
        direction = {v: k for k, v in DIRECTIONS.items()}.get(data1)
        if sensor is None or direction is None:
            raise CommandError(f"conveyor move with sensor {data0}, direction {data1}")
        return Command("MOVE_CONVEYOR", (direction, sensor))
    if station_type == "BS" and op == GET_BASE:
        colour = {v: k for k, v in BASE_CODES.items()}.get(data0)
        if colour is None:
            raise CommandError(f"get-base with unknown colour code {data0}")
        return Command("GET_BASE", (colour,))
    if station_type == "CS" and op == CAP_ACTION:
        what = {v: k for k, v in CAP_OPS.items()}.get(data0)
        if what is None:
            raise CommandError(f"cap action with unknown operation {data0}")
        return Command("CAP_ACTION", (what,))
    if station_type == "RS" and op == MOUNT_RING:
        if data0 not in (1, 2):
            raise CommandError(f"mount-ring from feeder {data0} (the RS has feeders 1 and 2)")
        return Command("MOUNT_RING", (data0, RING_ENUM.get(data1)))
    if station_type == "DS" and op == DELIVER:
        if data0 not in (1, 2, 3):
            raise CommandError(f"deliver to slot {data0} (slots 1..3)")
        return Command("DELIVER", (data0,))
    if station_type == "SS" and op in (SS_RETRIEVE, SS_STORE):
        return Command("RETRIEVE" if op == SS_RETRIEVE else "STORE",
                       (_shelf_slot(f"{data0},{data1}"),))
    if station_type == "SS" and op == SS_RELOCATE:
        return Command("RELOCATE", (_shelf_slot(f"{data0 // 10},{data0 % 10}"),
                                    _shelf_slot(f"{data1 // 10},{data1 % 10}")))
    raise CommandError(f"action id {action_id} is no command of a {station_type}")


__all__ = ["STEPS", "TYPE_BASE", "TYPE_CODE", "Command", "CommandError", "from_opcua", "parse_mqtt"]
