"""The cap station (CS): takes the cap off a capped workpiece into its buffer, or mounts
the buffered cap; cap carriers wait on its shelf."""
from __future__ import annotations

from dataclasses import dataclass

from ..world import SHELF_SLOTS, Workpiece
from .base import Station


@dataclass(frozen=True)
class CSInstruction:
    operation: str     # "RETRIEVE_CAP" | "MOUNT_CAP"



class CapStation(Station):
    kind, duration_key = "CS", "cs_process"

    def validate(self, instr) -> str | None:
        if not isinstance(instr, CSInstruction):
            return "prepare without cap station instruction"
        if instr.operation == "RETRIEVE_CAP":
            return "cannot retrieve while already holding a cap" if self.cap_buffer else None
        if instr.operation == "MOUNT_CAP":
            return None if self.cap_buffer else "cannot mount without a buffered cap"
        return f"invalid cap station operation {instr.operation}"

    def on_take(self, slot: str, wp: Workpiece | None) -> None:
        if slot in SHELF_SLOTS and self.host.config.refill_shelf:
            self.spawn_carrier(slot)
            return
        super().on_take(slot, wp)

    def carrier(self) -> Workpiece:
        cfg = self.host.config
        return Workpiece(cfg.carrier_base, (), cfg.cap_of(self.name[2:]))

    def spawn_carrier(self, slot: str) -> None:
        """Put a cap carrier on shelf ``slot`` unless something is there."""
        if self.host.world.workpiece_at(self.name, slot) is None:
            c = self.carrier()
            self.host.world.spawn_workpiece(self.name, slot, c.base, (), c.cap)

    def start(self, wp: Workpiece) -> str | None:
        if self.instruction.operation == "RETRIEVE_CAP" and wp.cap is None:
            return f"no cap to retrieve on {wp}"
        if self.instruction.operation == "MOUNT_CAP" and wp.cap is not None:
            return f"cannot mount a cap on capped {wp}"
        return None

    def finish(self) -> None:
        wp = self.inside
        if self.instruction.operation == "RETRIEVE_CAP":
            self.cap_buffer = wp.cap
            pts = self.host.profile.scoring.cap_retrieved
            if pts:
                self.host.award(self.team, pts, f"retrieved cap at {self.name}", machine=self.name)
            self._ready(wp.with_cap(None))
        else:
            cap, self.cap_buffer = self.cap_buffer, None
            self._ready(wp.with_cap(cap))
