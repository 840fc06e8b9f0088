"""The storage station (SS, 2017+): a shelf of 6 x 8 places inside the station.

PrepareMachine with an SS instruction (operation, shelf 0-5, slot 0-7,
optional ``wp_description``; the refbox's production.clp):

- ``STORE``: the station waits for a workpiece on its input, the belt takes it
  to the middle, it is stored at (shelf, slot) with the description
  (``storage_operation``), PROCESSED, then WAIT-IDLE for 5 s.  An occupied
  place breaks the station.
- ``RETRIEVE``: the station fetches the workpiece at (shelf, slot)
  (``storage_operation``; the place is then empty, its description gone),
  the belt takes it to the output, READY-AT-OUTPUT until a robot takes it,
  then WAIT-IDLE and IDLE.  An empty place breaks the station.
- ``CHANGE_INFO``: replaces the description of (shelf, slot) at once; the
  station stays IDLE.  Without a description nothing changes.
- A shelf or slot out of range, or an unknown operation, breaks the station.
- Slots pair up front to back: an odd slot lies behind the even one before it
  (``ss-slot-blocked-by``).  A back place whose front place is filled is out
  of reach: the station first *relocates* the front workpiece
  (``storage_operation``) to a random free place it can reach, or, when
  every free place is out of reach, the front workpiece of such a place
  into it; when nothing can move, the station breaks ("storage is full").
- Costs (profile scoring, 2025 -5 each): a store when it is done, a retrieve
  when the workpiece leaves the shelf, a relocation (0).
- At the start the profile's ``prestored`` products lie in it (2025: one C0
  of every base x cap pair at slot 1 of shelves 0-5).

Stored workpieces live here, not in the world (the world's SS has only an
input and an output slot); a break clears input and output, never the
shelf.  :meth:`StorageStation.status` is MachineInfo's ``status_ss``.
"""
from __future__ import annotations

from dataclasses import dataclass, field

from .. import events as E
from ..world import Workpiece
from .base import PROCESSED, PROCESSING, Station

SHELVES, SLOTS = 6, 8                    # SS-MAX-SHELF 5, SS-MAX-SLOT 7
OPERATIONS = ("STORE", "RETRIEVE", "CHANGE_INFO")
RELOCATE = "relocate"


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


def blocked_by(back: int, front: int) -> bool:
    """Whether slot ``back`` lies behind slot ``front`` (the refbox's ss-slot-blocked-by)."""
    return front == back - 1 and front % 2 == 0


def describe_product(wp: Workpiece) -> str:
    """A stored product's description as the refbox writes it ("BASE_RED CAP_GREY")."""
    return " ".join([wp.base, *wp.rings] + ([wp.cap] if wp.cap else []))


@dataclass
class StorageStation(Station):
    kind = "SS"
    shelf: dict = field(default_factory=dict)      # (shelf, slot) -> ShelfSlot, filled or described
    moving: tuple | None = None                    # a relocation under way: (from, to)
    _rng: object = None

    # -- reads ---------------------------------------------------------------------
    def place(self, shelf: int, slot: int) -> ShelfSlot:
        return self.shelf.get((shelf, slot)) or ShelfSlot(shelf, slot)

    def status(self) -> list[ShelfSlot]:
        """Every place, shelf by shelf and slot by slot (MachineInfo ``status_ss``)."""
        return [self.place(sh, sl) for sh in range(SHELVES) for sl in range(SLOTS)]

    def stored(self) -> dict[tuple[int, int], Workpiece]:
        return {k: p.workpiece for k, p in sorted(self.shelf.items()) if p.filled}

    def accessible(self, shelf: int, slot: int) -> bool:
        """Whether the arm reaches (shelf, slot): a front place, or a back place whose
        front place is empty."""
        return slot % 2 == 0 or not self.place(shelf, slot - 1).filled

    def put_in_storage(self, shelf: int, slot: int, wp: Workpiece, description: str = "") -> None:
        """Fill a place directly (a game set-up, not a robot's doing)."""
        self._check_place(shelf, slot)
        self.shelf[(shelf, slot)] = ShelfSlot(shelf, slot, wp, description or describe_product(wp))

    # -- Station hooks -------------------------------------------------------------
    def validate(self, instr) -> str | None:
        if not isinstance(instr, SSInstruction):
            return "without data"
        if instr.operation not in OPERATIONS:
            return f"with unknown storage operation {instr.operation}"
        try:
            self._check_place(instr.shelf, instr.slot)
        except ValueError as exc:
            return f"with {exc}"
        here = self.place(instr.shelf, instr.slot)
        if instr.operation == "RETRIEVE" and not here.filled:
            return f", but station is empty ({instr.shelf}, {instr.slot})"
        if instr.operation == "STORE" and here.filled:
            return f"with STORE operation for occupied shelf slot ({instr.shelf}, {instr.slot})"
        return None

    def wants_input(self) -> bool:
        return getattr(self.instruction, "operation", None) == "STORE"

    def prepare(self, instr) -> None:
        if isinstance(instr, SSInstruction) and instr.operation == "CHANGE_INFO" \
                and not self.validate(instr):
            if instr.description is not None:
                here = self.place(instr.shelf, instr.slot)
                self.shelf[(instr.shelf, instr.slot)] = ShelfSlot(
                    here.shelf, here.slot, here.workpiece, instr.description)
                self._emit(E.WORKPIECE, f"{self.name} ({instr.shelf}, {instr.slot}) is now "
                               f"{instr.description!r}", team=self.team, machine=self.name,
                               shelf=instr.shelf, slot=instr.slot)
            return
        super().prepare(instr)

    def on_prepared(self) -> None:
        self._route()

    def _route(self) -> None:
        """Relocate first when the place is out of reach, then retrieve, or wait for the
        workpiece to store."""
        ins = self.instruction
        if not self.accessible(ins.shelf, ins.slot):
            self._relocate_for(ins.shelf, ins.slot)
        elif ins.operation == "RETRIEVE":
            self._operate()
        else:
            self.step, self.deadline = "input", None

    def _relocate_for(self, shelf: int, slot: int) -> None:
        rng = self._rng or self.host.rng(f"storage/{self.name}")
        self._rng = rng
        reach = [(sh, sl) for sh in range(SHELVES) for sl in range(SLOTS)
                 if not self.place(sh, sl).filled and self.accessible(sh, sl)]
        if reach:
            move = ((shelf, slot - 1), rng.choice(reach))
        else:   # every free place is behind a filled one: move such a front one back
            backs = [(sh, sl) for sh in range(SHELVES) for sl in range(SLOTS)
                     if not self.place(sh, sl).filled and (sh, sl) != (shelf, slot)
                     and sl % 2 == 1]
            if not backs:
                self.break_(f"Prepare received for {self.name} for inaccessible slot while "
                            "the storage is full.", "storage-full")
                return
            sh, sl = rng.choice(backs)
            move = ((sh, sl - 1), (sh, sl))
        self.moving = move
        self._set_state(PROCESSING, f"relocating {move[0]} to {move[1]}")
        self._step(RELOCATE, self.times.storage_operation)

    def on_timer(self, step: str | None) -> None:
        if step != RELOCATE or self.moving is None:
            return
        src, dst = self.moving
        self.moving = None
        here = self.shelf.pop(src)
        self.shelf[dst] = ShelfSlot(dst[0], dst[1], here.workpiece, here.description)
        self._emit(E.WORKPIECE, f"{self.name} relocated {here.workpiece} from {src} to "
                       f"{dst}", team=self.team, machine=self.name, workpiece=here.workpiece,
                       what="relocated")
        self._pay("ss_relocate", f"relocating {src} to {dst} in {self.name}")
        self.proc_start = self.now
        self._route()

    def operation_time(self) -> float:
        return self.times.storage_operation

    def finish(self) -> None:
        ins = self.instruction
        key = (ins.shelf, ins.slot)
        if ins.operation == "STORE":
            wp, self.inside = self.inside, None
            desc = ins.description if ins.description is not None else describe_product(wp)
            self.shelf[key] = ShelfSlot(ins.shelf, ins.slot, wp, desc)
            self._emit(E.WORKPIECE, f"{self.name} stored {wp} at {key}", team=self.team,
                           machine=self.name, workpiece=wp, shelf=ins.shelf, slot=ins.slot)
            self._pay("ss_store", f"storing {key} at {self.name}")
            self._set_state(PROCESSED, "stored")
            self._wait_idle("stored")
            return
        here = self.shelf.pop(key)
        self._pay("ss_retrieve", f"retrieving {key} from {self.name}")
        self._processed(here.workpiece)

    def _pay(self, what: str, reason: str) -> None:
        pts = getattr(self.host.profile.scoring, what)
        if pts:
            self._award(self.team, pts, f"payment for {reason}", machine=self.name)

    @staticmethod
    def _check_place(shelf: int, slot: int) -> None:
        if not (0 <= int(shelf) < SHELVES and 0 <= int(slot) < SLOTS):
            raise ValueError(f"invalid shelf or slot ({shelf} [0, {SHELVES - 1}], "
                             f"{slot} [0, {SLOTS - 1}])")
