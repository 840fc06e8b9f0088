"""The delivery station (DS): consumes a workpiece and has the game judge the delivery."""
from __future__ import annotations

from dataclasses import dataclass

from .base import Station


@dataclass(frozen=True)
class DSInstruction:
    gate: int = 0               # 2016: 1-3 (0 = any)
    order_id: int | None = None  # 2017+: the order to deliver



class DeliveryStation(Station):
    kind, duration_key = "DS", "ds_deliver"

    def validate(self, instr) -> str | None:
        if not isinstance(instr, DSInstruction):
            return "prepare without delivery station instruction"
        return self.host.rules.validate_ds(self.host, instr)

    def finish(self) -> None:
        wp, self.inside = self.inside, None
        self.host.deliver(self, wp, self.host.rules.delivery_gate(self.host, self.instruction),
                          self.now)
        self._idle("delivered")
