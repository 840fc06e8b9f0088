"""The cap station (CS): takes the cap off a capped workpiece into its buffer, or mounts
the buffered cap; cap carriers wait on its shelf.

RETRIEVE_CAP while a cap is buffered, or MOUNT_CAP without one, breaks it
at the prepare.  The shelf holds three cap carriers (a base with the
station's cap colour); a human refills a shelf only once it is empty.
2025: a retrieved cap scores +2, and a break while it is buffered takes the
+2 back.
"""
from __future__ import annotations

from dataclasses import dataclass

from .. import events as E
from ..world import SHELF_SLOTS, Workpiece
from .base import Station


@dataclass(frozen=True)
class CSInstruction:
    operation: str     # "RETRIEVE_CAP" | "MOUNT_CAP"


class CapStation(Station):
    kind = "CS"

    def validate(self, instr) -> str | None:
        if not isinstance(instr, CSInstruction):
            return "without data"
        if instr.operation == "RETRIEVE_CAP":
            return ": cannot retrieve while already holding" if self.cap_buffer else None
        if instr.operation == "MOUNT_CAP":
            return None if self.cap_buffer else ": cannot mount without cap"
        return f"with invalid cap station operation {instr.operation}"

    def on_take(self, slot: str, wp: Workpiece | None) -> None:
        if slot in SHELF_SLOTS:
            if all(self.host.world.workpiece_at(self.name, s) is None for s in SHELF_SLOTS):
                self.fill_shelf()
                self._emit(E.WORKPIECE, f"{self.name} shelf empty: refilled", team=self.team,
                               machine=self.name, what="shelf-refilled")
            return
        super().on_take(slot, wp)

    def carrier(self) -> Workpiece:
        cfg = self.host.config
        return Workpiece(cfg.carrier_base, (), cfg.cap_of(self.name[2:]))

    def fill_shelf(self) -> None:
        """A cap carrier on every shelf place that is free."""
        for slot in SHELF_SLOTS:
            if self.host.world.workpiece_at(self.name, slot) is None:
                c = self.carrier()
                self.host.world.spawn_workpiece(self.name, slot, c.base, (), c.cap)

    def start(self, wp: Workpiece) -> tuple[str, str] | None:
        if self.instruction.operation == "RETRIEVE_CAP" and wp.cap is None:
            return f"{self.name}: no cap to retrieve on {wp}", "workpiece"
        if self.instruction.operation == "MOUNT_CAP" and wp.cap is not None:
            return f"{self.name}: cannot mount a cap on capped {wp}", "workpiece"
        return None

    def operation_time(self) -> float:
        return self.times.cap_operation

    def finish(self) -> None:
        wp = self.inside
        if self.instruction.operation == "RETRIEVE_CAP":
            self.cap_buffer = wp.cap
            pts = self.host.profile.scoring.cap_retrieved
            if pts:
                self._award(self.team, pts, f"retrieved cap at {self.name}", machine=self.name)
            self._processed(wp.with_cap(None))
        else:
            cap, self.cap_buffer = self.cap_buffer, None
            self._processed(wp.with_cap(cap))

    def revoke_points(self) -> None:
        pts = self.host.profile.scoring.cap_retrieved
        if self.cap_buffer and pts:
            self._award(self.team, -pts, f"deducting retrieved cap at {self.name}",
                            machine=self.name)
