"""The base station (BS): dispenses a base of the instructed colour on the instructed side."""
from __future__ import annotations

from dataclasses import dataclass

from rll_bt.rules import BASE_COLORS

from ..world import Workpiece
from .base import PROCESSING, Station


@dataclass(frozen=True)
class BSInstruction:
    side: str          # "INPUT" | "OUTPUT"
    color: str         # BASE_*



class BaseStation(Station):
    kind, duration_key = "BS", "bs_dispense"

    def validate(self, instr) -> str | None:
        if not isinstance(instr, BSInstruction):
            return "prepare without base station instruction"
        if instr.side not in ("INPUT", "OUTPUT"):
            return f"invalid side {instr.side}"
        if instr.color not in BASE_COLORS:
            return f"invalid base color {instr.color}"
        return None

    def on_prepared(self) -> None:
        # the BS goes straight to dispensing
        self._set_state(PROCESSING, f"dispensing {self.instruction.color}")
        self.deadline = self.now + self.duration

    def finish(self) -> None:
        side = self.instruction.side.lower()         # MachineSide INPUT/OUTPUT -> slot
        if self.host.world.workpiece_at(self.name, side) is not None:
            self.break_(f"cannot dispense, {side} is occupied")
            return
        self._ready(Workpiece(self.instruction.color), side)
