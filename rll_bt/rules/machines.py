"""How long the real machines take, and the refbox's own machine timings.

Machine durations are those of the Festo MPS as the referee box's mock-up
stations replay them (``src/libs/mps_comm/mockup/durations.h``, measured on
the real machines; refbox-rules.md "Machine processing times"); they are the
same under every rule set.  End to end a ring takes about 21.5 s from the
workpiece on the input to it on the output, a cap about 21.7 s, a base about
3.8 s.  The refbox's timings (``globals.clp``) are the time a BROKEN machine
stays out, the WAIT-IDLE after a product was taken and the green blink after
a prepare.
"""
from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class MachineTimes:
    """Seconds a machine takes for each step (no operation shorter than ``minimum``)."""

    base_dispense: float = 1.1            # BS: a base out of the magazine onto the belt
    belt_to_middle: float = 1.538         # conveyor input -> middle (under the tool)
    belt_to_output: float = 2.656         # conveyor middle -> output
    ring_mount: float = 17.308            # RS: mount one ring
    cap_operation: float = 17.5           # CS: retrieve or mount a cap
    storage_operation: float = 17.5       # SS: store, retrieve or relocate one workpiece
    delivery_slots: tuple[float, float, float] = (3.746, 4.746, 3.983)   # DS gate 1, 2, 3
    minimum: float = 1.0

    def delivery(self, gate: int) -> float:
        """The DS's time for ``gate`` (1-3; 0, any gate, takes gate 1's)."""
        g = int(gate)
        return self.delivery_slots[g - 1] if 1 <= g <= len(self.delivery_slots) \
            else self.delivery_slots[0]

    @property
    def base(self) -> float:
        """A base dispensed to the output (BS prepare -> READY-AT-OUTPUT)."""
        return self.base_dispense + self.belt_to_output

    @property
    def ring(self) -> float:
        """Workpiece on the input -> ringed workpiece at the output."""
        return self.belt_to_middle + self.ring_mount + self.belt_to_output

    @property
    def cap(self) -> float:
        """Workpiece on the input -> capped (or cap-less) workpiece at the output."""
        return self.belt_to_middle + self.cap_operation + self.belt_to_output

    @property
    def store(self) -> float:
        """Workpiece on the SS input -> on its shelf."""
        return self.belt_to_middle + self.storage_operation

    @property
    def retrieve(self) -> float:
        """SS prepare -> the workpiece at its output (without a relocation first)."""
        return self.storage_operation + self.belt_to_output


#: the Festo MPS of the league
MPS_TIMES = MachineTimes()

BROKEN_TIME = 30.0        # BROKEN-DOWN-TIME: a BROKEN machine is out this long
WAIT_IDLE_TIME = 5.0      # (RETRIEVE-)WAIT-IDLE-TIME: WAIT-IDLE before IDLE
PREPARED_BLINK_TIME = 3.0  # PREPARED-BLINK-TIME (2016 lights)
