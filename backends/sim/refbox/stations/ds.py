"""The delivery station (DS): consumes a workpiece and has the game judge the delivery.

2016: prepared with a gate, it takes the workpiece on its input (PROCESSING
for the gate's slot time), the delivery is judged, and it is IDLE again.
2025: prepared with an order id, it waits PREPARED until the order's window
has opened (order 0, consume only: at once), then PROCESSING for the
workpiece and its slot time; a workpiece put on it earlier stays on the
input, and the 20 s rule breaks a DS that waits too long.  After the
delivery it is PROCESSED, then WAIT-IDLE for 5 s.
"""
from __future__ import annotations

from dataclasses import dataclass

from ..world import Workpiece
from .base import INPUT_STEP, OPERATION, PROCESSED, PROCESSING, WINDOW, Station


@dataclass(frozen=True)
class DSInstruction:
    gate: int = 0               # 2016: 1-3 (0 = any)
    order_id: int | None = None  # 2017+: the order to deliver


class DeliveryStation(Station):
    kind = "DS"

    def validate(self, instr) -> str | None:
        if not isinstance(instr, DSInstruction):
            return "without data"
        return self.host.rules.validate_ds(self.host, instr)

    def gate(self) -> int:
        return self.host.rules.delivery_gate(self.host, self.instruction)

    def on_prepared(self) -> None:
        if not self.host.rules.ds_waits_for_window:
            return
        order_id = self.instruction.order_id
        order = self.host.order(order_id) if order_id else None
        if order is None or self.now >= order.begin:
            self._open()
        else:
            self.step, self.deadline = WINDOW, float(order.begin)

    def on_timer(self, step: str | None) -> None:
        if step == WINDOW:
            self._open()

    def _open(self) -> None:
        """The window is open: deliver the workpiece on the input, or wait for one."""
        self._set_state(PROCESSING, f"delivering to gate {self.gate()}")
        self.step, self.deadline = INPUT_STEP, None

    def on_input(self, wp: Workpiece) -> None:
        if self.state != PROCESSING:
            self._set_state(PROCESSING, f"delivering to gate {self.gate()}")
        self._step(OPERATION, self.times.delivery(self.gate()))

    def finish(self) -> None:
        wp, self.inside = self.inside, None
        self.host.deliver(self, wp, self.gate(), self.now)
        if self.host.profile.wait_idle_after_delivery:
            self._set_state(PROCESSED, "delivered")
            self._wait_idle("delivered")
        else:
            self._idle("delivered")
