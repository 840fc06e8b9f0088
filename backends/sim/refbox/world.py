"""The world as the refbox sees it, and an in-memory world.

The refbox needs little from a world: where the stations stand, a way to set
their signal towers, to spawn, swap and remove workpieces at station slots,
and to hear when a robot puts a workpiece on a slot or takes one off.
:class:`RefboxWorld` is that interface; the PyBullet world implements it
through an adapter, and :class:`TableWorld` implements it with dictionaries,
so the game logic runs and is tested without physics.

Slots: ``INPUT`` and ``OUTPUT`` (conveyor ends), ``SLIDE`` (ring station
additional-base slide) and ``SHELF0..2`` (cap station shelf).  Colours are
the ``llsf_msgs`` enum names (``BASE_RED``, ``RING_BLUE``, ``CAP_GREY``);
lights map ``RED``/``YELLOW``/``GREEN`` to ``ON``/``OFF``/``BLINK``.
"""
from __future__ import annotations

from dataclasses import dataclass, field, replace
from typing import Callable, Mapping, Protocol, runtime_checkable

INPUT, OUTPUT, SLIDE = "INPUT", "OUTPUT", "SLIDE"
SHELF_SLOTS = ("SHELF0", "SHELF1", "SHELF2")
SLOTS = (INPUT, OUTPUT, SLIDE) + SHELF_SLOTS
PUT, TAKE = "put", "take"
ON, OFF, BLINK = "ON", "OFF", "BLINK"
LIGHT_COLORS = ("RED", "YELLOW", "GREEN")


def lights(red: str = OFF, yellow: str = OFF, green: str = OFF) -> dict[str, str]:
    """A full signal-tower setting, e.g. ``lights(green=ON)``."""
    return {"RED": red, "YELLOW": yellow, "GREEN": green}


ALL_OFF = lights()


@dataclass(frozen=True)
class Workpiece:
    """A product in the making: a base, up to three rings (bottom first), a cap.

    ``uid`` lets a world keep track of its bodies; it takes no part in
    equality.
    """

    base: str
    rings: tuple[str, ...] = ()
    cap: str | None = None
    uid: int | None = field(default=None, compare=False)

    def with_ring(self, color: str) -> "Workpiece":
        return replace(self, rings=self.rings + (color,))

    def with_cap(self, color: str) -> "Workpiece":
        return replace(self, cap=color)

    def without_cap(self) -> "Workpiece":
        return replace(self, cap=None)

    def __str__(self) -> str:
        parts = [self.base] + list(self.rings) + ([self.cap] if self.cap else [])
        return "+".join(parts)


@dataclass(frozen=True)
class SlotEvent:
    """A robot ``put`` a workpiece on, or ``take`` one off, ``machine``'s ``slot``."""

    kind: str
    machine: str
    slot: str
    workpiece: Workpiece | None = None


@runtime_checkable
class RefboxWorld(Protocol):
    """What the refbox needs from a world."""

    def layout(self):
        """Every station of both teams, as placed: a
        :class:`backends.sim.layout.FieldLayout` (``layout[m].zone``,
        ``.rotation_deg``, ``.pose``)."""

    def set_lights(self, machine: str, lights: Mapping[str, str]) -> None:
        """Show ``lights`` (RED/YELLOW/GREEN -> ON/OFF/BLINK) on ``machine``'s tower."""

    def spawn_workpiece(self, machine: str, slot: str, wp: Workpiece) -> None:
        """Put ``wp`` on ``machine``'s ``slot`` (replacing what is there)."""

    def remove_workpiece(self, machine: str, slot: str) -> Workpiece | None:
        """Take away whatever is on ``machine``'s ``slot``; None when empty."""

    def workpiece_at(self, machine: str, slot: str) -> Workpiece | None:
        """What is on ``machine``'s ``slot`` now."""

    def add_slot_listener(self, fn: Callable[[SlotEvent], None]) -> None:
        """Call ``fn`` when a robot puts a workpiece on a slot or takes one off."""


class TableWorld:
    """An in-memory :class:`RefboxWorld`: stations placed by ``layout`` (a
    :class:`backends.sim.layout.FieldLayout`), workpieces in a dictionary,
    lights remembered.  :meth:`put` and :meth:`take` play the robot's part and
    notify the listeners, as a physical world would.
    """

    def __init__(self, layout):
        self._layout = layout
        self.slots: dict[tuple[str, str], Workpiece] = {}
        self.lights: dict[str, dict[str, str]] = {m: dict(ALL_OFF) for m in layout.machines}
        self._listeners: list[Callable[[SlotEvent], None]] = []
        self._uid = 0

    @classmethod
    def generated(cls, profile, seed: int) -> "TableWorld":
        """A table world with the seeded layout of the PyBullet world's generator
        (:func:`backends.sim.layout.generate_layout`)."""
        from ..layout import generate_layout
        return cls(generate_layout(profile, seed))

    # -- RefboxWorld -----------------------------------------------------------
    def layout(self):
        return self._layout

    def set_lights(self, machine: str, lights: Mapping[str, str]) -> None:
        self._check(machine)
        self.lights[machine] = dict(lights)

    def spawn_workpiece(self, machine: str, slot: str, wp: Workpiece) -> None:
        self._check(machine, slot)
        if wp.uid is None:
            self._uid += 1
            wp = replace(wp, uid=self._uid)
        self.slots[(machine, slot)] = wp

    def remove_workpiece(self, machine: str, slot: str) -> Workpiece | None:
        self._check(machine, slot)
        return self.slots.pop((machine, slot), None)

    def workpiece_at(self, machine: str, slot: str) -> Workpiece | None:
        self._check(machine, slot)
        return self.slots.get((machine, slot))

    def add_slot_listener(self, fn: Callable[[SlotEvent], None]) -> None:
        self._listeners.append(fn)

    # -- the robot's side --------------------------------------------------------
    def put(self, machine: str, slot: str, wp: Workpiece) -> None:
        """A robot puts ``wp`` on ``machine``'s ``slot``; ValueError if it is occupied."""
        self._check(machine, slot)
        if (machine, slot) in self.slots:
            raise ValueError(f"{machine} {slot} is occupied by {self.slots[(machine, slot)]}")
        self.spawn_workpiece(machine, slot, wp)
        self._notify(SlotEvent(PUT, machine, slot, self.slots[(machine, slot)]))

    def take(self, machine: str, slot: str) -> Workpiece:
        """A robot takes the workpiece off ``machine``'s ``slot``; ValueError if empty."""
        self._check(machine, slot)
        wp = self.slots.pop((machine, slot), None)
        if wp is None:
            raise ValueError(f"nothing on {machine} {slot}")
        self._notify(SlotEvent(TAKE, machine, slot, wp))
        return wp

    def _notify(self, ev: SlotEvent) -> None:
        for fn in list(self._listeners):
            fn(ev)

    def _check(self, machine: str, slot: str | None = None) -> None:
        if machine not in self._layout.machines:
            raise KeyError(f"no station {machine!r} in this world")
        if slot is not None and slot not in SLOTS:
            raise KeyError(f"no slot {slot!r} (slots: {', '.join(SLOTS)})")
