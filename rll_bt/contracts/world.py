"""The world contract: the field, its robots and its stations on one clock.

What a game steps and its robots drive: a simulated world (PyBullet), and
tomorrow a world feeding device emulators or a recorded one.  It knows
nothing of the referee box's game (that is :mod:`.refbox`).

Times are seconds of :attr:`World.clock`; poses are field-frame metres and
radians of the rules profile.
"""
from __future__ import annotations

import abc
from typing import Any

from ..backend import Backend, Pose2D

#: a world feeding device emulators that stands further behind the wall clock than this (s)
#: casts and renders nothing until it caught up (a scan stamped with the time the world stands at
#: is right however old, but it is of no use to a robot that has moved on, and the world's process
#: needs the time to catch up); nearer, the devices' own lateness never stops a laser.  The game
#: that runs such a world counts the time it spent further behind (games/hardware.py).
STALE_CAST = 0.5


class World(abc.ABC):
    """``profile``: the rules profile (:class:`rll_bt.rules.Profile`);
    ``clock``: the clock only :meth:`step` advances (a
    :class:`~rll_bt.clock.SimClock` for a simulated world); ``seed``: what
    fixed the layout and the noise."""

    profile: Any
    clock: Any
    seed: int

    @abc.abstractmethod
    def step(self, dt: float) -> None:
        """Advance the world ``dt`` seconds (this moves the clock)."""

    @abc.abstractmethod
    def backend(self, team: str, number: int, **options) -> Backend:
        """The backend of robot ``number`` of ``team`` (added to the world on
        first use, with ``options``; later calls give the same robot)."""

    @abc.abstractmethod
    def robot_pose(self, team: str, number: int) -> Pose2D:
        """Where the robot really is (ground truth)."""

    def emulated_hardware(self, *, laser: str = "urg", camera_fps: float = 5.0, devices: str = "threads"):
        """The robots as device emulators fed by this world (``rll-bt sim
        --hardware emulated``): an object with ``add((team, number))`` -> a
        rig with ``config()`` (a robot configuration for the ``robotino``
        backend), ``sync()`` (after every step, on the thread that steps),
        ``stats()`` and ``stop()``.  ``devices``: "threads" (in the world's
        process) or "process" (each robot's devices in a process of their own)."""
        raise NotImplementedError(f"{type(self).__name__} emulates no hardware")

    def collision_log(self) -> list[tuple[float, str, str]]:
        """Every collision so far: (time, robot "TEAM/N", what it ran into: a
        station's name, "wall" or "robot TEAM/N")."""
        return []

    def laser_sightings(self) -> dict[str, dict[str, int]]:
        """Per robot ("TEAM/N"), the other robots ("TEAM/N") its laser has
        seen so far and in how many scans: what a robot can know of another
        team's robots (empty where the world does not count them)."""
        return {}

    def close(self) -> None:
        pass
