"""The ring station (RS): mounts a ring of one of its two colours, paid with additional
bases loaded on its slide.

A ring colour the RS lacks breaks it at the prepare.  The colour's cost in
bases must be on the slide: 2016 checks when the workpiece comes in, 2025
at the prepare (the refbox asks the referee, who breaks it with
auto-break-machines on).  Each base on the slide scores +2 up to 3 loaded;
a 4th breaks the machine.  2025: bases fed into a BROKEN RS do not count,
and a break takes back +2 per unused base.
"""
from __future__ import annotations

from dataclasses import dataclass

from ..world import SLIDE, Workpiece
from .base import BROKEN, Station


@dataclass(frozen=True)
class RSInstruction:
    ring_color: str    # RING_*


class RingStation(Station):
    kind = "RS"

    def validate(self, instr) -> str | None:
        if not isinstance(instr, RSInstruction):
            return "without data"
        if instr.ring_color not in self.host.rs_colors(self.name):
            return f"for invalid ring color ({instr.ring_color})"
        return None

    def on_prepared(self) -> None:
        if self.host.profile.rs_paid_at_prepare:
            unpaid = self._unpaid()
            if unpaid:
                self.break_(unpaid, "insufficient-bases")

    def on_put(self, slot: str, wp, robot=None) -> None:
        if slot == SLIDE and self.active:
            self.host.world.remove_workpiece(self.name, SLIDE, getattr(wp, "id", None))
            self.load_slide()
            return
        super().on_put(slot, wp, robot)

    def load_slide(self) -> None:
        """One additional base fed to the slide: +``additional_base`` points, or BROKEN
        when more than ``slide_max`` would be loaded."""
        rules = self.host.rules
        if self.state == BROKEN and not rules.slide_counts_while_broken:
            return                                  # 2025: not counted, no points
        if self.slide_loaded + 1 > self.host.config.slide_max:
            if rules.slide_counts_while_broken:
                self.bases_added += 1               # 2016 counts it anyway
            if self.state != BROKEN:
                self.break_(f"{self.name}: too many additional bases loaded", "too-many-bases")
            return
        self.bases_added += 1
        self._award(self.team, self.host.profile.scoring.additional_base,
                        f"added additional base to {self.name}", machine=self.name)

    def _unpaid(self) -> str | None:
        color = self.instruction.ring_color
        need = self.host.ring_cost(color)
        if self.slide_loaded < need:
            return f"{self.name}: insufficient bases ({self.slide_loaded} < {need})"
        return None

    def start(self, wp: Workpiece) -> tuple[str, str] | None:
        if not self.host.profile.rs_paid_at_prepare:
            unpaid = self._unpaid()
            if unpaid:
                return unpaid, "insufficient-bases"
        if wp.cap is not None or len(wp.rings) >= 3:
            return f"{self.name}: cannot mount a ring on {wp}", "workpiece"
        self.bases_used += self.host.ring_cost(self.instruction.ring_color)
        return None

    def operation_time(self) -> float:
        return self.times.ring_mount

    def finish(self) -> None:
        self._processed(self.inside.with_ring(self.instruction.ring_color))

    def revoke_points(self) -> None:
        unused = self.slide_loaded
        if unused > 0:
            self._award(self.team, -unused * self.host.profile.scoring.additional_base,
                            f"deducting unused additional bases at {self.name}",
                            machine=self.name)
