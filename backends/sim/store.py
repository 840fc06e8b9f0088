"""Where every workpiece is, and its body in the world.

A workpiece is at a station slot (``("slot", machine, slot)``), in a robot's
gripper, or on the floor.  The store keeps slot capacities (one workpiece,
many on an RS slide), rebuilds a workpiece's body when its rings or cap
change, and moves held workpieces with their robot.
"""
from __future__ import annotations

import itertools
import math
from dataclasses import dataclass

from rll_bt.rules import WORKPIECE

from .bullet import ShapeCache
from .stations import Station
from .workpieces import Location, Workpiece, build_body, move_body, remove_body


class SlotError(ValueError):
    """A slot is full, empty, or does not exist."""


@dataclass
class _Entry:
    workpiece: Workpiece
    location: Location
    body: int
    position: tuple[float, float, float]       # bottom centre, field frame


class WorkpieceStore:
    def __init__(self, cid: int, shapes: ShapeCache, stations: dict[str, Station]):
        self.cid = cid
        self.shapes = shapes
        self.stations = stations
        self._entries: dict[int, _Entry] = {}
        self._slots: dict[tuple[str, str], list[int]] = {}
        self._ids = itertools.count(1)

    # -- queries ------------------------------------------------------------
    def station(self, machine: str) -> Station:
        try:
            return self.stations[machine]
        except KeyError:
            raise KeyError(f"no station {machine!r} (known: {', '.join(sorted(self.stations))})") from None

    def at(self, machine: str, slot: str) -> tuple[Workpiece, ...]:
        self.station(machine).slot(slot)
        return tuple(self._entries[i].workpiece for i in self._slots.get((machine, slot), ()))

    def get(self, wp_id: int) -> Workpiece:
        return self._entries[wp_id].workpiece

    def location(self, wp_id: int) -> Location:
        return self._entries[wp_id].location

    def position(self, wp_id: int) -> tuple[float, float, float]:
        return self._entries[wp_id].position

    def all(self) -> list[tuple[Workpiece, Location]]:
        return [(e.workpiece, e.location) for _, e in sorted(self._entries.items())]

    def loose(self):
        """(id, bottom-centre position) of every workpiece not in a gripper."""
        return [(i, e.position) for i, e in self._entries.items() if e.location.kind != "robot"]

    def free_capacity(self, machine: str, slot: str) -> int:
        cap = self.station(machine).slot(slot).capacity
        return cap - len(self._slots.get((machine, slot), ()))

    # -- changes ------------------------------------------------------------
    def new_id(self) -> int:
        return next(self._ids)

    def slot_position(self, machine: str, slot: str, index: int) -> tuple[float, float, float]:
        st = self.station(machine)
        x, y, z = st.slot(slot).local
        if slot == "slide":               # further workpieces queue down the slide
            x -= 0.045 * index
        return st.to_world(x, y, z)

    def put(self, wp: Workpiece, machine: str, slot: str) -> Workpiece:
        """Place ``wp`` (new or currently held/on the floor) at a slot."""
        if self.free_capacity(machine, slot) <= 0:
            raise SlotError(f"{machine} {slot} is full")
        ids = self._slots.setdefault((machine, slot), [])
        pos = self.slot_position(machine, slot, len(ids))
        self._place(wp, Location("slot", machine=machine, slot=slot), pos)
        ids.append(wp.id)
        return wp

    def put_floor(self, wp: Workpiece, x: float, y: float) -> Workpiece:
        self._place(wp, Location("floor", xy=(x, y)), (x, y, 0.0))
        return wp

    def hold(self, wp_id: int, robot: tuple[str, int], position) -> Workpiece:
        e = self._entries[wp_id]
        self._unslot(wp_id)
        e.location = Location("robot", robot=robot)
        self.move(wp_id, position)
        return e.workpiece

    def move(self, wp_id: int, position) -> None:
        e = self._entries[wp_id]
        if e.position != position:
            e.position = tuple(position)
            move_body(self.cid, e.body, position)

    def take(self, machine: str, slot: str, wp_id: int | None = None) -> Workpiece | None:
        """Remove a workpiece (the first at the slot, or ``wp_id``) from the world."""
        ids = self._slots.get((machine, slot), [])
        self.station(machine).slot(slot)
        if not ids:
            return None
        if wp_id is None:
            wp_id = ids[0]
        elif wp_id not in ids:
            raise SlotError(f"workpiece {wp_id} is not at {machine} {slot}")
        return self.delete(wp_id)

    def delete(self, wp_id: int) -> Workpiece:
        e = self._entries.pop(wp_id)
        self._unslot(wp_id, e)
        remove_body(self.cid, e.body)
        return e.workpiece

    def replace(self, new: Workpiece) -> Workpiece:
        """Swap a workpiece's description (rings, cap) and rebuild its body."""
        e = self._entries[new.id]
        remove_body(self.cid, e.body)
        e.workpiece = new
        e.body = build_body(self.cid, self.shapes, new, e.position)
        return new

    def _place(self, wp: Workpiece, loc: Location, pos) -> None:
        e = self._entries.get(wp.id)
        if e is None:
            self._entries[wp.id] = _Entry(wp, loc, build_body(self.cid, self.shapes, wp, pos), tuple(pos))
            return
        self._unslot(wp.id, e)
        e.location = loc
        self.move(wp.id, pos)

    def _unslot(self, wp_id: int, e: _Entry | None = None) -> None:
        e = e or self._entries[wp_id]
        if e.location.kind != "slot":
            return
        key = (e.location.machine, e.location.slot)
        ids = self._slots.get(key, [])
        if wp_id in ids:
            ids.remove(wp_id)
            for k, other in enumerate(ids):     # close the queue on a slide
                self.move(other, self.slot_position(key[0], key[1], k))


def grab_height(position) -> float:
    """Height at which a gripper holds a workpiece standing at ``position``."""
    return position[2] + WORKPIECE.base_height / 2.0


def horizontal(a, b) -> float:
    return math.hypot(a[0] - b[0], a[1] - b[1])
