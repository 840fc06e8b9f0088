"""The simulator contract: the world and the simulated refbox of a game.

Games never import the simulator by name: they find it through the entry
point group ``rll_bt.simulators``, a factory returning a :class:`Simulation`.

- :class:`Simulation` (``rll_bt.simulators``): the world, its robots and the
  simulated referee box on one :class:`~rll_bt.clock.SimClock`.  The
  factory is called as ``factory(profile=..., seed=..., team_name=...,
  key=..., perception=..., gui=..., phases={...}, world_step=...,
  robot_options={...})``, and with ``refbox="process"`` for a game whose
  refbox runs as its own process (``rll-bt sim --processes``): the
  simulation then holds the world only, gives the command line of the
  refbox process (:meth:`Simulation.refbox_command`) and reads the game
  from what that process writes.

Times are seconds of the simulation clock unless named *game time* (the
refbox's seconds into the current phase).  Poses are field-frame metres and
radians of the rules profile.
"""
from __future__ import annotations

import abc
from collections.abc import Callable
from pathlib import Path
from typing import Any

from ..backend import Backend, Pose2D
from .refbox import Award, Delivery, GameStatus, StationTruth

SIMULATORS = "rll_bt.simulators"


class Simulation(abc.ABC):
    """World, robots and simulated refbox on one clock (see the module doc)."""

    profile: Any          #: the rules profile (:class:`rll_bt.rules.Profile`)
    clock: Any            #: the :class:`~rll_bt.clock.SimClock` only :meth:`step` advances
    seed: int

    # -- wiring ----------------------------------------------------------------
    @abc.abstractmethod
    def attach_bus(self, bus) -> None:
        """Put the refbox on an in-process :class:`rll_bt.comm.Bus`: channels
        "public", "cyan", "magenta" and the control stream at "refbox"."""

    def refbox_command(self, *, host: str, layout, snapshot: Path, message_log: Path | None = None) -> list[str]:
        """With ``refbox="process"``: the ``rll-bt`` arguments of the refbox
        process, on UDP sending to ``host`` on ``layout`` (a
        :class:`rll_bt.comm.Layout`, the refbox's view), rewriting the
        ``snapshot`` file the status, awards, deliveries, stations and orders
        are read from, and logging every message it sends and receives to
        ``message_log`` (JSON lines of :mod:`.msglog`, on the monotonic wall
        clock).  :meth:`refbox_step` then serves that process."""
        raise NotImplementedError

    def refbox_ready(self) -> bool:
        """Whether the refbox is up (with ``refbox="process"``: it wrote its first snapshot)."""
        return True

    def refbox_registry(self):
        """The refbox message registry (for logging what its channels carry)."""
        raise NotImplementedError

    @abc.abstractmethod
    def start(self) -> None:
        """Start the game (the operator's RUNNING)."""

    @abc.abstractmethod
    def step(self, dt: float) -> None:
        """Advance the world ``dt`` seconds (this moves the clock)."""

    @abc.abstractmethod
    def refbox_step(self) -> None:
        """The refbox receives, ticks its game and sends what is due (with
        ``refbox="process"``: the refbox process's calls on the world are served)."""

    # -- robots ------------------------------------------------------------------
    @abc.abstractmethod
    def backend(self, team: str, number: int, **options) -> Backend:
        """Robot ``number`` of ``team`` (added to the world on first use)."""

    @abc.abstractmethod
    def robot_pose(self, team: str, number: int) -> Pose2D:
        """Ground truth."""

    def collisions(self) -> int:
        return 0

    def collision_log(self) -> list[tuple[float, str, str]]:
        """(time, robot "TEAM/N", what it ran into: a machine, "wall" or "robot TEAM/N")."""
        return []

    # -- reading the game ------------------------------------------------------------
    @abc.abstractmethod
    def status(self) -> GameStatus: ...

    @abc.abstractmethod
    def awards(self) -> list[Award]: ...

    @abc.abstractmethod
    def deliveries(self) -> list[Delivery]: ...

    @abc.abstractmethod
    def stations(self) -> dict[str, StationTruth]: ...

    def orders(self) -> list[dict]:
        """The game's orders as plain dicts (id, complexity, quantity, window)."""
        return []

    # -- faults --------------------------------------------------------------------
    def station_down(self, machine: str, seconds: float) -> None:
        """Take a station DOWN now for ``seconds`` of game time."""
        raise NotImplementedError

    def close(self) -> None:
        pass


SimulatorFactory = Callable[..., Simulation]


def load_simulator(name: str) -> SimulatorFactory:
    """The ``rll_bt.simulators`` entry point ``name``; KeyError names the installed ones."""
    from .. import plugins
    return plugins.load(SIMULATORS, name)

