"""The ring station (RS): mounts a ring of one of its two colours, paid with additional
bases loaded on its slide."""
from __future__ import annotations

from dataclasses import dataclass

from ..world import SLIDE, Workpiece
from .base import BROKEN, Station


@dataclass(frozen=True)
class RSInstruction:
    ring_color: str    # RING_*



class RingStation(Station):
    kind, duration_key = "RS", "rs_mount"

    def validate(self, instr) -> str | None:
        if not isinstance(instr, RSInstruction):
            return "prepare without ring station instruction"
        colors = self.host.rs_colors(self.name)
        if instr.ring_color not in colors:
            return f"invalid ring color {instr.ring_color} (has {', '.join(colors)})"
        return None

    def on_put(self, slot: str, wp) -> None:
        if slot == SLIDE and self.active:
            self.host.world.remove_workpiece(self.name, SLIDE, getattr(wp, "id", None))
            self.load_slide()
            return
        super().on_put(slot, wp)

    def load_slide(self) -> None:
        """One additional base fed to the slide: +``additional_base`` points, or BROKEN
        when more than ``slide_max`` are loaded."""
        self.bases_added += 1
        if self.slide_loaded > self.host.config.slide_max:
            if self.state != BROKEN:
                self.break_(f"too many additional bases loaded ({self.slide_loaded})")
            return
        self.host.award(self.team, self.host.profile.scoring.additional_base,
                        f"added additional base to {self.name}", machine=self.name)

    def start(self, wp: Workpiece) -> str | None:
        color = self.instruction.ring_color
        need = self.host.ring_cost(color)
        if self.slide_loaded < need:
            return f"insufficient bases ({self.slide_loaded} < {need}) for {color}"
        if wp.cap is not None or len(wp.rings) >= 3:
            return f"cannot mount a ring on {wp}"
        self.bases_used += need
        return None

    def finish(self) -> None:
        self._ready(self.inside.with_ring(self.instruction.ring_color))
