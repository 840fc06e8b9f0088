"""All stations of a world run as machines, with a thread-safe inbox.

Network front ends (MQTT, OPC-UA) receive commands on their own threads and
:meth:`MachineHall.submit` them; the world's owner calls
:meth:`MachineHall.update` after each world step, on the world's thread,
which hands the commands to the machines and advances them.  Feedback
goes to every listener added with :meth:`add_listener` (called on the
world's thread; a front end queues it for its own thread).
"""
from __future__ import annotations

import queue
from collections.abc import Callable, Iterable

from .commands import Command
from .machine import Durations, Feedback, MpsMachine, Product

#: the storage station's filled slots at the start of a 2025 game: six C0
#: products, every base with every cap, in slot 1 of shelves 0..5 (the
#: refbox's ``default-storage``)
DEFAULT_STORAGE = {
    (0, 1): Product("BASE_RED", (), "CAP_GREY"), (1, 1): Product("BASE_RED", (), "CAP_BLACK"),
    (2, 1): Product("BASE_SILVER", (), "CAP_GREY"), (3, 1): Product("BASE_SILVER", (), "CAP_BLACK"),
    (4, 1): Product("BASE_BLACK", (), "CAP_GREY"), (5, 1): Product("BASE_BLACK", (), "CAP_BLACK"),
}


def default_feeders(profile, machine: str) -> tuple[str, str] | None:
    """The ring colours of an RS's two feeders under ``profile`` (fixed in
    2025: RS1 orange/green, RS2 blue/yellow; None where the rules draw
    them per game, as 2016's)."""
    colours = getattr(profile, "rs_colors", None) or {}
    return colours.get(machine.split("-", 1)[1])


class MachineHall:
    """Machines for ``machines`` of ``world`` (default: all its stations).

    ``feeders`` {machine: (colour 1, colour 2)} overrides the profile's
    RS feeders; ``storage`` the SS contents at the start (default
    :data:`DEFAULT_STORAGE` on every SS); ``shelves`` {CS: carrier}: keep
    that CS's shelf slots filled with cap carriers (a field's referee does,
    where no simulated refbox puts them there), each one taken replaced at
    the next update."""

    def __init__(self, world, machines: Iterable[str] | None = None, *,
                 durations: Durations | None = None,
                 feeders: dict[str, tuple[str, str]] | None = None,
                 storage: dict[tuple[int, int], Product] | None = None,
                 shelves: dict[str, Product] | None = None):
        self.world = world
        names = sorted(machines) if machines is not None else list(world.machines)
        unknown = [m for m in names if m not in world.machines]
        if unknown:
            raise KeyError(f"no station {', '.join(unknown)} in the world "
                           f"(known: {', '.join(world.machines)})")
        self.shelves = dict(shelves or {})         # CS -> the cap carrier its shelf slots are kept filled with
        self._inbox: queue.SimpleQueue = queue.SimpleQueue()
        self._listeners: list[Callable[[Feedback], None]] = []
        profile = getattr(world, "profile", None)
        feeders = feeders or {}
        self.machines: dict[str, MpsMachine] = {}
        for name in names:
            kind = world.station(name).type
            self.machines[name] = MpsMachine(
                world, name, self._emit, durations=durations,
                feeders=feeders.get(name) or (default_feeders(profile, name) if kind == "RS" else None),
                storage=(DEFAULT_STORAGE if storage is None else storage) if kind == "SS" else None)

    def __getitem__(self, name: str) -> MpsMachine:
        return self.machines[name]

    def __iter__(self):
        return iter(self.machines.values())

    def set_feeders(self, machine: str, colours: tuple[str, str]) -> None:
        """Which ring colours an RS's feeders hold (e.g. from the refbox's MachineInfo)."""
        self.machines[machine].feeders = tuple(colours)

    def add_listener(self, fn: Callable[[Feedback], None]) -> None:
        self._listeners.append(fn)

    def remove_listener(self, fn: Callable[[Feedback], None]) -> None:
        self._listeners.remove(fn)

    def _emit(self, fb: Feedback) -> None:
        for fn in list(self._listeners):
            fn(fb)

    def submit(self, machine: str, command: Command) -> None:
        """Queue ``command`` for ``machine`` (any thread)."""
        if machine not in self.machines:
            raise KeyError(f"no machine {machine!r} served (served: {', '.join(self.machines)})")
        self._inbox.put((machine, command))

    def update(self) -> None:
        """Hand queued commands to the machines and advance them to the world's time."""
        now = self.world.time
        while True:
            try:
                machine, command = self._inbox.get_nowait()
            except queue.Empty:
                break
            self.machines[machine].command(command, now)
        for m in self.machines.values():
            m.update(now)
        for name, carrier in self.shelves.items():
            for slot in self.world.station(name).slots:
                if slot.startswith("shelf") and self.world.workpiece_at(name, slot) is None:
                    self.world.spawn_workpiece(name, slot, carrier.base, carrier.rings, carrier.cap)


__all__ = ["DEFAULT_STORAGE", "MachineHall", "default_feeders"]
