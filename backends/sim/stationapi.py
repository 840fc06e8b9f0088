"""The station API the simulated referee box drives (a mixin of
:class:`~backends.sim.world.World`): lights, workpieces at station slots, and
the events of robots putting workpieces on slots or taking them off.  See
the package docstring for the list.
"""
from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

from .stations import Station
from .store import SlotError
from .workpieces import Location, Workpiece

_KEEP = object()


@dataclass(frozen=True)
class SlotEvent:
    """A robot put a workpiece at a station slot (``kind="put"``), took one
    from it (``kind="take"``) or let one fall on the floor (``kind="drop"``,
    machine and slot None)."""
    kind: str
    machine: str | None
    slot: str | None
    workpiece: Workpiece
    robot: tuple[str, int]
    time: float


class StationAPI:
    """Needs ``store``, ``stations``, ``time``, ``blink_hz``, ``gui``,
    ``_show_lights``, ``_events`` and ``_listeners`` from the world."""

    def station(self, machine: str) -> Station:
        return self.store.station(machine)

    @property
    def machines(self) -> list[str]:
        return sorted(self.stations)

    def set_lights(self, machine: str, *, red: str = "OFF", yellow: str = "OFF", green: str = "OFF") -> None:
        """Set all three lights of a station ("OFF", "ON" or "BLINK")."""
        self.station(machine).set_lights(RED=red, YELLOW=yellow, GREEN=green)
        if self.gui:
            self._show_lights()

    def lights(self, machine: str) -> dict[str, str]:
        """The station's light settings, e.g. {"RED": "OFF", "YELLOW": "BLINK", "GREEN": "ON"}."""
        return dict(self.station(machine).lights)

    def visible_light_code(self, machine: str) -> int:
        """Lights lit right now (blink phase applied) as green 1 + yellow 2 + red 4."""
        return self.station(machine).light_code(self.time, self.blink_hz)

    def spawn_workpiece(self, machine: str, slot: str, base: str, rings=(), cap: str | None = None) -> Workpiece:
        """A new workpiece at a station slot (e.g. a base dispensed at the BS output)."""
        wp = Workpiece(self.store.new_id(), base, tuple(rings), cap)
        return self.store.put(wp, machine, slot)

    def spawn_workpiece_on_floor(self, x: float, y: float, base: str, rings=(), cap: str | None = None) -> Workpiece:
        wp = Workpiece(self.store.new_id(), base, tuple(rings), cap)
        return self.store.put_floor(wp, x, y)

    def remove_workpiece(self, machine: str, slot: str, workpiece_id: int | None = None) -> Workpiece | None:
        """Take a workpiece out of the world (the first at the slot, or the
        given one); None when the slot is empty."""
        return self.store.take(machine, slot, workpiece_id)

    def modify_workpiece(self, machine: str, slot: str, *, add_ring: str | None = None,
                         rings=None, cap=_KEEP) -> Workpiece:
        """Change the workpiece at a slot: ``add_ring`` mounts a ring on top,
        ``rings`` replaces the ring list, ``cap`` sets the cap colour (None
        removes the cap: a cap retrieved).  Returns the new description."""
        here = self.store.at(machine, slot)
        if not here:
            raise SlotError(f"{machine} {slot} is empty")
        wp = here[0]
        if rings is not None:
            wp = Workpiece(wp.id, wp.base, tuple(rings), wp.cap)
        if add_ring is not None:
            wp = wp.with_ring(add_ring)
        if cap is not _KEEP:
            wp = wp.with_cap(cap)
        return self.store.replace(wp)

    def move_workpiece(self, machine: str, src: str, dst: str) -> Workpiece:
        """Move the workpiece at ``src`` to ``dst`` of the same station (the
        conveyor carrying it from input to output)."""
        here = self.store.at(machine, src)
        if not here:
            raise SlotError(f"{machine} {src} is empty")
        return self.store.put(here[0], machine, dst)

    def workpiece_at(self, machine: str, slot: str) -> Workpiece | None:
        here = self.store.at(machine, slot)
        return here[0] if here else None

    def workpieces_at(self, machine: str, slot: str) -> tuple[Workpiece, ...]:
        return self.store.at(machine, slot)

    def workpieces(self) -> list[tuple[Workpiece, Location]]:
        """Every workpiece in the world and where it is."""
        return self.store.all()

    def add_slot_listener(self, fn: Callable[[SlotEvent], None]) -> None:
        """Call ``fn(event)`` after each step in which a robot put a workpiece
        at a slot or took one from it (events in order of occurrence)."""
        self._listeners.append(fn)

    def remove_slot_listener(self, fn: Callable[[SlotEvent], None]) -> None:
        self._listeners.remove(fn)

    def _fire_events(self) -> None:
        while self._events:
            ev = self._events.pop(0)
            for fn in list(self._listeners):
                fn(ev)

