"""The storage station (SS, 2017+): a shelf of 6 x 8 places inside the station.

PrepareMachine with an SS instruction (operation, shelf 0-5, slot 0-7,
optional ``wp_description``; the refbox's production.clp):

- ``STORE``: the station waits for a workpiece on its input, takes it in
  (``ss_process`` game seconds) and keeps it at (shelf, slot) with the
  description; then IDLE.  An occupied place breaks the station.
- ``RETRIEVE``: the station brings the workpiece at (shelf, slot) to its
  output (``ss_process`` s; the place is then empty, its description gone),
  READY-AT-OUTPUT until a robot takes it, then WAIT-IDLE and IDLE.  An empty
  place breaks the station.
- ``CHANGE_INFO``: replaces the description of (shelf, slot) at once; the
  station stays IDLE.  Without a description nothing changes.
- A shelf or slot out of range, or an unknown operation, breaks the station.

Stored workpieces live here, not in the world (the world's SS has only an
input and an output slot); a break clears input and output, never the
shelf.  :meth:`StorageStation.status` is MachineInfo's ``status_ss``.
"""
from __future__ import annotations

from dataclasses import dataclass, field

from .. import events as E
from ..world import OUTPUT, Workpiece
from .base import Station

SHELVES, SLOTS = 6, 8                    # SS-MAX-SHELF 5, SS-MAX-SLOT 7
OPERATIONS = ("STORE", "RETRIEVE", "CHANGE_INFO")


@dataclass(frozen=True)
class SSInstruction:
    operation: str                       # "STORE" | "RETRIEVE" | "CHANGE_INFO"
    shelf: int
    slot: int
    description: str | None = None


@dataclass(frozen=True)
class ShelfSlot:
    """One storage place: its workpiece (None when empty) and description."""

    shelf: int
    slot: int
    workpiece: Workpiece | None = None
    description: str = ""

    @property
    def filled(self) -> bool:
        return self.workpiece is not None


@dataclass
class StorageStation(Station):
    kind, duration_key = "SS", "ss_process"
    shelf: dict = field(default_factory=dict)      # (shelf, slot) -> ShelfSlot, filled or described

    # -- reads ---------------------------------------------------------------------
    def place(self, shelf: int, slot: int) -> ShelfSlot:
        return self.shelf.get((shelf, slot)) or ShelfSlot(shelf, slot)

    def status(self) -> list[ShelfSlot]:
        """Every place, shelf by shelf and slot by slot (MachineInfo ``status_ss``)."""
        return [self.place(sh, sl) for sh in range(SHELVES) for sl in range(SLOTS)]

    def stored(self) -> dict[tuple[int, int], Workpiece]:
        return {k: p.workpiece for k, p in sorted(self.shelf.items()) if p.filled}

    def put_in_storage(self, shelf: int, slot: int, wp: Workpiece, description: str = "") -> None:
        """Fill a place directly (a game set-up, not a robot's doing)."""
        self._check_place(shelf, slot)
        self.shelf[(shelf, slot)] = ShelfSlot(shelf, slot, wp, description)

    # -- Station hooks -------------------------------------------------------------
    def validate(self, instr) -> str | None:
        if not isinstance(instr, SSInstruction):
            return "prepare without storage station instruction"
        if instr.operation not in OPERATIONS:
            return f"unknown storage operation {instr.operation}"
        try:
            self._check_place(instr.shelf, instr.slot)
        except ValueError as exc:
            return str(exc)
        here = self.place(instr.shelf, instr.slot)
        if instr.operation == "RETRIEVE" and not here.filled:
            return f"station is empty at ({instr.shelf}, {instr.slot})"
        if instr.operation == "STORE" and here.filled:
            return f"STORE for occupied shelf slot ({instr.shelf}, {instr.slot})"
        return None

    def prepare(self, instr) -> None:
        if isinstance(instr, SSInstruction) and instr.operation == "CHANGE_INFO" \
                and not self.validate(instr):
            if instr.description is not None:
                here = self.place(instr.shelf, instr.slot)
                self.shelf[(instr.shelf, instr.slot)] = ShelfSlot(
                    here.shelf, here.slot, here.workpiece, instr.description)
                self.host.emit(E.WORKPIECE, f"{self.name} ({instr.shelf}, {instr.slot}) is now "
                               f"{instr.description!r}", team=self.team, machine=self.name,
                               shelf=instr.shelf, slot=instr.slot)
            return
        super().prepare(instr)

    def on_prepared(self) -> None:
        if self.instruction.operation == "RETRIEVE":
            self._processing()              # nothing to wait for: fetch from the shelf

    def start(self, wp: Workpiece) -> str | None:
        return None                         # STORE takes whatever lies on the input

    def finish(self) -> None:
        ins = self.instruction
        key = (ins.shelf, ins.slot)
        if ins.operation == "STORE":
            wp, self.inside = self.inside, None
            desc = ins.description if ins.description is not None else self.place(*key).description
            self.shelf[key] = ShelfSlot(ins.shelf, ins.slot, wp, desc)
            self.host.emit(E.WORKPIECE, f"{self.name} stored {wp} at {key}", team=self.team,
                           machine=self.name, workpiece=wp, shelf=ins.shelf, slot=ins.slot)
            self._idle("stored")
            return
        if self.host.world.workpiece_at(self.name, OUTPUT) is not None:
            self.break_("cannot retrieve, the output is occupied")
            return
        here = self.shelf.pop(key)
        self._ready(here.workpiece)

    @staticmethod
    def _check_place(shelf: int, slot: int) -> None:
        if not (0 <= int(shelf) < SHELVES and 0 <= int(slot) < SLOTS):
            raise ValueError(f"invalid shelf or slot ({shelf} [0, {SHELVES - 1}], "
                             f"{slot} [0, {SLOTS - 1}])")
