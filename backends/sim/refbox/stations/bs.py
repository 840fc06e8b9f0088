"""The base station (BS): dispenses a base of the instructed colour on the instructed side.

Prepared, it dispenses at once (PROCESSING, ``base_dispense``), then the
belt carries the base to the side (PROCESSED: to the output, or back to the
input), READY-AT-OUTPUT until a robot takes it.  A side already occupied
breaks it.
"""
from __future__ import annotations

from dataclasses import dataclass

from rll_bt.rules import BASE_COLORS

from ..world import INPUT, OUTPUT, Workpiece
from .base import OPERATION, PROCESSING, Station


@dataclass(frozen=True)
class BSInstruction:
    side: str          # "INPUT" | "OUTPUT"
    color: str         # BASE_*


class BaseStation(Station):
    kind = "BS"

    def validate(self, instr) -> str | None:
        if not isinstance(instr, BSInstruction):
            return "without data"
        if instr.side not in ("INPUT", "OUTPUT"):
            return f"with invalid side {instr.side}"
        if instr.color not in BASE_COLORS:
            return f"with invalid base color {instr.color}"
        return None

    def wants_input(self) -> bool:
        return False

    def on_prepared(self) -> None:
        # the BS goes straight to dispensing
        self._set_state(PROCESSING, f"dispensing {self.instruction.color}")
        self._step(OPERATION, self.times.base_dispense)

    def finish(self) -> None:
        side = INPUT if self.instruction.side == "INPUT" else OUTPUT
        move = self.times.belt_to_output if side == OUTPUT else self.times.belt_to_middle
        self._processed(Workpiece(self.instruction.color), side, move)
