"""One station of the world run as a Festo MPS: commands in, feedback out,
on the world's clock.

The model is what a referee box sees of a real station (its PLC): one step
command at a time (a conveyor move, a base dispensed, a cap or ring
operation, a delivery, a storage operation), busy while it works, the
workpiece sensor at the output, the slide counter of a ring station.
Lights and RESET act at once.  Work happens in the world through its
station API: the belt carries the workpiece from the ``input`` slot to the
``output`` slot, a base is spawned, a cap or ring changes the workpiece, a
delivered or stored workpiece leaves the world.

The world has no slot in the middle of the belt: a workpiece "at MID"
stays at the world's ``input`` slot (where a robot put it) with
``at_mid`` set, until it moves on.

Feedback (:class:`Feedback`) is what the refbox subscribes to: ``busy``
(MQTT ``Status`` BUSY/IDLE, OPC-UA ``Status/Busy``), ``ready`` (``WP-Sensor``
WP/NoWP, ``Status/Ready``), ``slide`` (``SlideCount``/``SlideCnt``) and
``barcode``.  Each is sent when it changes, in the order it changed.
"""
from __future__ import annotations

from collections import deque
from collections.abc import Callable
from dataclasses import dataclass, field

from .commands import Command

#: base colour word of the wire -> the world's colour name
BASES = {"RED": "BASE_RED", "BLACK": "BASE_BLACK", "SILVER": "BASE_SILVER"}


@dataclass(frozen=True)
class Durations:
    """Seconds a step takes.  Defaults: the refbox's measurements of the
    Festo MPS (its mock-up durations, ``reference/refbox-rules.md``)."""
    min_operation: float = 1.0
    belt_in_to_mid: float = 1.538
    belt_mid_to_out: float = 2.656
    base_dispense: float = 1.1
    cap: float = 17.5
    ring: float = 17.308
    storage: float = 17.5
    deliver: tuple[float, float, float] = (3.746, 4.746, 3.983)

    def scaled(self, factor: float) -> Durations:
        """Every duration times ``factor`` (but at least 0)."""
        f = max(0.0, float(factor))
        return Durations(self.min_operation * f, self.belt_in_to_mid * f, self.belt_mid_to_out * f,
                         self.base_dispense * f, self.cap * f, self.ring * f, self.storage * f,
                         tuple(d * f for d in self.deliver))


@dataclass(frozen=True)
class Feedback:
    """``what`` is "busy", "ready", "slide" or "barcode"; ``value`` a bool or int."""
    machine: str
    what: str
    value: bool | int
    time: float


@dataclass(frozen=True)
class Product:
    """A workpiece's description away from the world (in a storage station)."""
    base: str
    rings: tuple[str, ...] = ()
    cap: str | None = None


@dataclass
class _Job:
    command: Command
    started: float
    done: float | None = None            # None: waiting for a workpiece


@dataclass
class Record:
    """A thing the station did (for logs and tests)."""
    time: float
    text: str
    data: dict = field(default_factory=dict)


class MpsMachine:
    """Station ``name`` of ``world`` (type from the world's station).

    ``feeders``: the ring colours on feeder 1 and 2 of an RS (MQTT names only
    the feeder); ``storage``: the SS's filled shelf slots at the start
    ({(shelf, slot): Product}).  Call :meth:`command` when a command
    arrives and :meth:`update` after each world step; feedback goes to the
    ``emit`` callable."""

    def __init__(self, world, name: str, emit: Callable[[Feedback], None], *,
                 durations: Durations | None = None, feeders: tuple[str, str] | None = None,
                 storage: dict[tuple[int, int], Product] | None = None):
        self.world, self.name, self._emit = world, name, emit
        self.kind = world.station(name).type
        self.durations = durations or Durations()
        self.feeders = tuple(feeders) if feeders else None
        self.storage: dict[tuple[int, int], Product] = dict(storage or {})
        self.busy = False
        self.ready = False
        self.slide_count = 0
        self.barcode = 0
        self.at_mid = False
        self.cap_buffer: str | None = None
        self.declared_type: str | None = None
        self.delivered: list[Record] = []
        self.records: list[Record] = []
        self._queue: deque[Command] = deque()
        self._job: _Job | None = None
        self._seen_input: int | None = None

    # -- inputs -----------------------------------------------------------------
    def command(self, cmd: Command, now: float) -> None:
        """A command from the refbox, at world time ``now``."""
        a = cmd.action
        if a == "NOTHING":
            return
        self._record(now, f"command {a} {' '.join(map(str, cmd.args))}".rstrip(), command=cmd)
        if a == "LIGHT":
            if cmd.args[0] == "RESET":
                self.world.set_lights(self.name)
            else:
                lights = dict(self.world.lights(self.name))
                lights[cmd.args[0]] = cmd.args[1]
                self.world.set_lights(self.name, red=lights["RED"], yellow=lights["YELLOW"],
                                      green=lights["GREEN"])
        elif a == "SET_TYPE":
            self.declared_type = cmd.args[0]
            if cmd.args[0] != self.kind:
                self._record(now, f"told it is a {cmd.args[0]}, but it is a {self.kind}")
        elif a == "RESET":
            self._reset(now)
        else:
            self._queue.append(cmd)
            self._start_next(now)

    def update(self, now: float) -> None:
        """Advance to world time ``now``: sense, finish and start steps."""
        self._sense(now)
        job = self._job
        if job is not None and job.done is None and self._has_workpiece():
            job.done = now + self._duration(job.command)
        if job is not None and job.done is not None and now >= job.done - 1e-9:
            self._job = None
            self._finish(job.command, now)
            self._sense(now)
            self._set("busy", False, now)
            self._start_next(now)

    # -- state --------------------------------------------------------------------
    def _start_next(self, now: float) -> None:
        if self._job is not None or not self._queue:
            return
        cmd = self._queue.popleft()
        # a belt move and a delivery wait for a workpiece (the PLC's input sensor)
        waits = ((cmd.action == "MOVE_CONVEYOR" and not self._has_workpiece())
                 or (cmd.action == "DELIVER" and self._at("input") is None))
        self._job = _Job(cmd, now, None if waits else now + self._duration(cmd))
        self._set("busy", True, now)
        if cmd.action == "MOVE_CONVEYOR" and not waits:
            self._sense(now)

    def _reset(self, now: float) -> None:
        self._queue.clear()
        self._job = None
        if self.at_mid:
            wp = self.world.remove_workpiece(self.name, "input")
            self.at_mid = False
            if wp is not None:
                self._record(now, f"reset: workpiece {wp.id} taken off the belt", workpiece=wp)
        self._set("busy", False, now)
        self._sense(now)

    def _set(self, what: str, value, now: float) -> None:
        attr = {"busy": "busy", "ready": "ready", "slide": "slide_count", "barcode": "barcode"}[what]
        if getattr(self, attr) == value:
            return
        setattr(self, attr, value)
        self._emit(Feedback(self.name, what, value, now))

    def _record(self, now: float, text: str, **data) -> None:
        self.records.append(Record(now, text, data))

    def state(self) -> dict:
        """Every register the refbox reads, for reconnecting clients."""
        return {"busy": self.busy, "ready": self.ready, "slide": self.slide_count,
                "barcode": self.barcode}

    # -- the world ------------------------------------------------------------------
    def _slots(self) -> tuple[str, ...]:
        return tuple(self.world.station(self.name).slots)

    def _at(self, slot: str):
        return self.world.workpiece_at(self.name, slot) if slot in self._slots() else None

    def _has_workpiece(self) -> bool:
        return self._at("input") is not None or self._at("output") is not None

    def _sense(self, now: float) -> None:
        """Read the sensors: the output light barrier, the input's barcode
        scanner and the ring station's slide counter."""
        slots = self._slots()
        if "slide" in slots:
            for wp in self.world.workpieces_at(self.name, "slide"):
                self.world.remove_workpiece(self.name, "slide", wp.id)
                self._record(now, f"base {wp.id} counted on the slide", workpiece=wp)
                self._set("slide", self.slide_count + 1, now)
        wp_in = self._at("input")
        if wp_in is None:
            self.at_mid = False
            self._seen_input = None
        elif wp_in.id != self._seen_input:
            self._seen_input = wp_in.id
            self._set("barcode", wp_in.id, now)
        moving = self._job is not None and self._job.command.action == "MOVE_CONVEYOR"
        ready = not moving and (self._at("output") is not None
                                or (self.kind == "BS" and wp_in is not None and not self.at_mid))
        self._set("ready", ready, now)

    def _duration(self, cmd: Command) -> float:
        d, a = self.durations, cmd.action
        if a == "MOVE_CONVEYOR":
            target = cmd.args[1]
            at = "OUT" if self._at("output") is not None else ("MID" if self.at_mid else "IN")
            legs = {("IN", "MID"): d.belt_in_to_mid, ("MID", "OUT"): d.belt_mid_to_out,
                    ("IN", "OUT"): d.belt_in_to_mid + d.belt_mid_to_out}
            t = legs.get((at, target)) or legs.get((target, at)) or 0.0
            return max(d.min_operation, t)
        table = {"GET_BASE": d.base_dispense, "CAP_ACTION": d.cap, "MOUNT_RING": d.ring,
                 "RETRIEVE": d.storage, "STORE": d.storage, "RELOCATE": d.storage}
        if a == "DELIVER":
            return max(d.min_operation, d.deliver[cmd.args[0] - 1])
        return max(d.min_operation, table[a])

    def _finish(self, cmd: Command, now: float) -> None:
        a, args = cmd.action, cmd.args
        if a == "MOVE_CONVEYOR":
            self._move(args[1], now)
        elif a == "GET_BASE":
            if self._at("input") is not None:
                self._record(now, "no base dispensed: the belt is occupied")
                return
            wp = self.world.spawn_workpiece(self.name, "input", BASES[args[0]])
            self.at_mid = True
            self._seen_input = wp.id
            self._set("barcode", wp.id, now)           # the scanner reads the new base
            self._record(now, f"base {wp.id} {wp.base} dispensed", workpiece=wp)
        elif a == "CAP_ACTION":
            self._cap(args[0], now)
        elif a == "MOUNT_RING":
            self._ring(args[0], args[1], now)
        elif a == "DELIVER":
            wp = self.world.remove_workpiece(self.name, "input")
            if wp is None:
                self._record(now, f"deliver to slot {args[0]}: no workpiece")
                return
            rec = Record(now, f"workpiece {wp.id} delivered to slot {args[0]}",
                         {"workpiece": wp, "slot": args[0]})
            self.delivered.append(rec)
            self.records.append(rec)
        else:
            self._storage(a, args, now)

    def _move(self, target: str, now: float) -> None:
        wp = self._at("input")
        if target == "OUT" and wp is not None and "output" in self._slots():
            if self._at("output") is None:
                self.world.move_workpiece(self.name, "input", "output")
                self.at_mid = False
                self._record(now, f"workpiece {wp.id} at the output", workpiece=wp)
            else:
                self._record(now, "belt stopped: the output is occupied")
        elif target == "MID" and wp is not None:
            self.at_mid = True
            self._record(now, f"workpiece {wp.id} in the middle", workpiece=wp)
        elif target == "IN":
            if wp is None and self._at("output") is not None:
                wp = self.world.move_workpiece(self.name, "output", "input")
            self.at_mid = False
            if wp is not None:
                self._record(now, f"workpiece {wp.id} at the input", workpiece=wp)

    def _cap(self, op: str, now: float) -> None:
        wp = self._at("input")
        if wp is None or not self.at_mid:
            self._record(now, f"cap {op.lower()}: no workpiece in the middle")
            return
        if op == "RETRIEVE":
            if wp.cap is None:
                self._record(now, f"cap retrieve: workpiece {wp.id} has no cap")
                return
            self.cap_buffer = wp.cap
            wp = self.world.modify_workpiece(self.name, "input", cap=None)
            self._record(now, f"cap {self.cap_buffer} buffered from workpiece {wp.id}", workpiece=wp)
        elif self.cap_buffer is None:
            self._record(now, f"cap mount: no cap buffered for workpiece {wp.id}")
        elif wp.cap is not None:
            self._record(now, f"cap mount: workpiece {wp.id} already has a cap")
        else:
            wp = self.world.modify_workpiece(self.name, "input", cap=self.cap_buffer)
            self.cap_buffer = None
            self._record(now, f"cap {wp.cap} mounted on workpiece {wp.id}", workpiece=wp)

    def _ring(self, feeder: int, colour: str | None, now: float) -> None:
        wp = self._at("input")
        if colour is None:
            if self.feeders is None:
                self._record(now, f"mount ring: feeder {feeder} has no colour configured")
                return
            colour = self.feeders[feeder - 1]
        if wp is None or not self.at_mid:
            self._record(now, "mount ring: no workpiece in the middle")
            return
        if len(wp.rings) >= 3 or wp.cap is not None:
            self._record(now, f"mount ring: workpiece {wp.id} takes no more rings")
            return
        wp = self.world.modify_workpiece(self.name, "input", add_ring=colour)
        self._record(now, f"ring {colour} mounted on workpiece {wp.id}", workpiece=wp)

    def _storage(self, a: str, args, now: float) -> None:
        if a == "RELOCATE":
            src, dst = args
            if src in self.storage and dst not in self.storage:
                self.storage[dst] = self.storage.pop(src)
                self._record(now, f"relocated shelf slot {src} to {dst}")
            else:
                self._record(now, f"relocate {src} -> {dst}: not possible")
            return
        (where,) = args
        if a == "STORE":
            wp = self._at("input")
            if wp is None or not self.at_mid or where in self.storage:
                self._record(now, f"store at {where}: no workpiece in the middle or the slot is full")
                return
            self.world.remove_workpiece(self.name, "input")
            self.at_mid = False
            self.storage[where] = Product(wp.base, wp.rings, wp.cap)
            self._record(now, f"workpiece {wp.id} stored at {where}", workpiece=wp)
            return
        product = self.storage.get(where)
        if product is None or self._at("input") is not None:
            self._record(now, f"retrieve from {where}: the slot is empty or the belt occupied")
            return
        del self.storage[where]
        wp = self.world.spawn_workpiece(self.name, "input", product.base, product.rings, product.cap)
        self.at_mid = True
        self._seen_input = wp.id
        self._set("barcode", wp.id, now)               # the scanner reads the retrieved product
        self._record(now, f"workpiece {wp.id} retrieved from {where}", workpiece=wp)


__all__ = ["BASES", "Durations", "Feedback", "MpsMachine", "Product", "Record"]
