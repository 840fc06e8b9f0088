"""The world as the refbox sees it, and an in-memory world.

The refbox needs little from a world: where the stations stand, a way to set
their signal towers, to spawn and remove workpieces at station slots, and to
hear when a robot puts a workpiece on a slot or takes one off.
:class:`RefboxWorld` is that interface.  It is the station API of the
PyBullet world (:class:`backends.sim.world.World`), which therefore plugs in
as is, and :class:`TableWorld` implements it with dictionaries, so the game
logic runs and is tested without physics.

Slots (as the PyBullet world): ``input``; ``output`` (not on a DS);
``slide`` (RS, holds many); ``shelf0``..``shelf2`` (CS).  The storage
station (2025) has only ``input`` and ``output``: what it stores is kept by
the refbox (:mod:`.stations.ss`), not in the world.  Colours are the
``llsf_msgs`` enum names (``BASE_RED``, ``RING_BLUE``, ``CAP_GREY``); lights
are ``OFF``/``ON``/``BLINK`` for ``RED``, ``YELLOW``, ``GREEN``.
"""
from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field, replace
from typing import Protocol, runtime_checkable

INPUT, OUTPUT, SLIDE = "input", "output", "slide"
SHELF_SLOTS = ("shelf0", "shelf1", "shelf2")
PUT, TAKE, DROP = "put", "take", "drop"
ON, OFF, BLINK = "ON", "OFF", "BLINK"
LIGHT_COLORS = ("RED", "YELLOW", "GREEN")


def station_slots(machine: str) -> tuple[str, ...]:
    """The slots of ``machine`` ("C-RS1" -> input, output, slide)."""
    kind = machine[2:4]
    return {"DS": (INPUT,), "RS": (INPUT, OUTPUT, SLIDE),
            "CS": (INPUT, OUTPUT) + SHELF_SLOTS}.get(kind, (INPUT, OUTPUT))


def lights(red: str = OFF, yellow: str = OFF, green: str = OFF) -> dict[str, str]:
    """A full signal-tower setting, e.g. ``lights(green=ON)``."""
    return {"RED": red, "YELLOW": yellow, "GREEN": green}


ALL_OFF = lights()


@dataclass(frozen=True)
class Workpiece:
    """A product in the making: a base, up to three rings (bottom first), a cap.

    ``id`` is the world's handle; it takes no part in equality, so a
    workpiece compares equal to its description.  The PyBullet world has its
    own workpiece class with the same ``base``/``rings``/``cap`` fields; the
    refbox only reads those.
    """

    base: str
    rings: tuple[str, ...] = ()
    cap: str | None = None
    id: int | None = field(default=None, compare=False)

    def with_ring(self, color: str) -> Workpiece:
        return replace(self, rings=tuple(self.rings) + (color,))

    def with_cap(self, color: str | None) -> Workpiece:
        return replace(self, cap=color)

    def __str__(self) -> str:
        return "+".join([self.base, *self.rings] + ([self.cap] if self.cap else []))


def describe(wp) -> Workpiece:
    """Any world's workpiece as a refbox :class:`Workpiece` (base, rings, cap)."""
    return Workpiece(wp.base, tuple(wp.rings), wp.cap, getattr(wp, "id", None))


@dataclass(frozen=True)
class SlotEvent:
    """A robot ``put`` a workpiece on, or ``take`` one off, ``machine``'s ``slot``, or
    ``drop`` ped it on the floor (machine and slot None); ``robot`` is (team colour,
    number) when the world knows who."""

    kind: str
    machine: str | None
    slot: str | None
    workpiece: object = None
    robot: tuple[str, int] | None = None


class WorldLost(RuntimeError):
    """The world can no longer be reached (its process ended, the link
    broke): the refbox stops.  Never taken for a world quirk and swallowed."""


@runtime_checkable
class RefboxWorld(Protocol):
    """What the refbox needs from a world (the PyBullet world's station API).

    ``layout``: a :class:`backends.sim.layout.FieldLayout` (``layout[m].zone``,
    ``.rotation_deg``, ``.pose``; ``layout.machines``).
    """

    layout: object

    def set_lights(self, machine: str, *, red: str = OFF, yellow: str = OFF,
                   green: str = OFF) -> None:
        """Show the lights on ``machine``'s tower (OFF, ON or BLINK each)."""

    def spawn_workpiece(self, machine: str, slot: str, base: str, rings=(), cap=None):
        """A new workpiece on ``machine``'s ``slot``; ValueError if the slot is full."""

    def remove_workpiece(self, machine: str, slot: str, workpiece_id=None):
        """Take the (first) workpiece off ``machine``'s ``slot``; None when empty."""

    def workpiece_at(self, machine: str, slot: str):
        """The (first) workpiece on ``machine``'s ``slot``, None when empty."""

    def add_slot_listener(self, fn: Callable) -> None:
        """Call ``fn(event)`` (``event.kind`` "put"/"take", ``.machine``, ``.slot``,
        ``.workpiece``) when a robot puts a workpiece on a slot or takes one off."""


class TableWorld:
    """An in-memory :class:`RefboxWorld`: stations placed by ``layout`` (a
    :class:`backends.sim.layout.FieldLayout`), workpieces in lists per slot,
    lights remembered.  :meth:`put` and :meth:`take` play the robot's part and
    notify the listeners, as the PyBullet world does after a gripper acts.
    """

    def __init__(self, layout):
        self.layout = layout
        self._slots: dict[tuple[str, str], list[Workpiece]] = {}
        self._lights: dict[str, dict[str, str]] = {m: dict(ALL_OFF) for m in layout.machines}
        self._listeners: list[Callable] = []
        self._ids = 0

    @classmethod
    def generated(cls, profile, seed: int) -> TableWorld:
        """A table world with the seeded layout of the PyBullet world's generator
        (:func:`backends.sim.layout.generate_layout`)."""
        from ..layout import generate_layout
        return cls(generate_layout(profile, seed))

    # -- RefboxWorld -----------------------------------------------------------
    def set_lights(self, machine: str, *, red: str = OFF, yellow: str = OFF,
                   green: str = OFF) -> None:
        self._check(machine)
        self._lights[machine] = lights(red, yellow, green)

    def lights(self, machine: str) -> dict[str, str]:
        self._check(machine)
        return dict(self._lights[machine])

    def spawn_workpiece(self, machine: str, slot: str, base: str, rings=(), cap=None) -> Workpiece:
        self._ids += 1
        return self._place(machine, slot, Workpiece(base, tuple(rings), cap, self._ids))

    def remove_workpiece(self, machine: str, slot: str, workpiece_id=None):
        here = self._here(machine, slot)
        for i, wp in enumerate(here):
            if workpiece_id is None or wp.id == workpiece_id:
                return here.pop(i)
        return None

    def workpiece_at(self, machine: str, slot: str):
        here = self._here(machine, slot)
        return here[0] if here else None

    def workpieces_at(self, machine: str, slot: str) -> tuple:
        return tuple(self._here(machine, slot))

    def add_slot_listener(self, fn: Callable) -> None:
        self._listeners.append(fn)

    # -- the robot's side --------------------------------------------------------
    def put(self, machine: str, slot: str, wp, robot: tuple[str, int] | None = None) -> Workpiece:
        """A robot (``robot``: (team colour, number)) puts ``wp`` on ``machine``'s ``slot``;
        ValueError if it is full."""
        if getattr(wp, "id", None) is None:
            self._ids += 1
            wp = replace(describe(wp), id=self._ids)
        wp = self._place(machine, slot, wp)
        self._notify(SlotEvent(PUT, machine, slot, wp, robot))
        return wp

    def take(self, machine: str, slot: str, robot: tuple[str, int] | None = None):
        """A robot takes the (first) workpiece off ``machine``'s ``slot``; ValueError if empty."""
        here = self._here(machine, slot)
        if not here:
            raise ValueError(f"nothing on {machine} {slot}")
        wp = here.pop(0)
        self._notify(SlotEvent(TAKE, machine, slot, wp, robot))
        return wp

    def drop(self, wp, robot: tuple[str, int] | None = None) -> None:
        """A robot lets ``wp`` fall on the floor (it leaves this world)."""
        self._notify(SlotEvent(DROP, None, None, wp, robot))

    def _place(self, machine: str, slot: str, wp):
        here = self._here(machine, slot)
        if here and slot != SLIDE:
            raise ValueError(f"{machine} {slot} is occupied by {here[0]}")
        here.append(wp)
        return wp

    def _here(self, machine: str, slot: str) -> list:
        self._check(machine)
        if slot not in station_slots(machine):
            raise KeyError(f"{machine} has no slot {slot!r} "
                           f"(slots: {', '.join(station_slots(machine))})")
        return self._slots.setdefault((machine, slot), [])

    def _notify(self, ev: SlotEvent) -> None:
        for fn in list(self._listeners):
            fn(ev)

    def _check(self, machine: str) -> None:
        if machine not in self.layout.machines:
            raise KeyError(f"no station {machine!r} in this world")
