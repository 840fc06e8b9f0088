"""The two plug-in interfaces a simulated game is made of.

``rll_bt`` never imports the simulator or the team server by name: it finds
them through entry points (groups ``rll_bt.simulators`` and
``rll_bt.teamservers``), each a factory returning an object with the small
interface below.

- :class:`Simulation` (``rll_bt.simulators``): the world, its robots and the
  simulated referee box on one :class:`~rll_bt.clock.SimClock`.  The
  factory is called as ``factory(profile=..., seed=..., team_name=...,
  key=..., perception=..., gui=..., phases={...}, world_step=...,
  robot_options={...})``, and with ``refbox="process"`` for a game whose
  refbox runs as its own process (``rll-bt sim --processes``): the
  simulation then holds the world only, gives the command line of the
  refbox process (:meth:`Simulation.refbox_command`) and reads the game
  from what that process writes.
- :class:`TeamServerHandle` (``rll_bt.teamservers``): an in-process team
  server.  Called as ``factory(profile=..., team_name=..., key=...,
  clock=..., refbox_public=..., refbox_team=..., agents=..., state=...,
  strategy=..., seed=..., oracle=..., options=...)`` where ``refbox_team``
  is ``color -> Transport`` and ``agents`` a zero-argument factory of the
  stream server the agents connect to (called again on a restart).

Times are seconds of the simulation clock unless named *game time* (the
refbox's seconds into the current phase).  Poses are field-frame metres and
radians of the rules profile.
"""
from __future__ import annotations

import abc
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from ..backend import Backend, Pose2D

SIMULATORS = "rll_bt.simulators"
TEAMSERVERS = "rll_bt.teamservers"


@dataclass(frozen=True)
class GameStatus:
    """The refbox's view right now: ``phase`` ("SETUP", "EXPLORATION",
    "PRODUCTION", "POST_GAME", ...), ``state`` ("RUNNING", "PAUSED", ...),
    ``game_time`` (game seconds into the phase), ``phase_length`` (None
    when the phase has no end), ``points`` per team colour."""

    phase: str
    state: str
    game_time: float
    phase_length: float | None
    points: dict[str, int]


@dataclass(frozen=True)
class Award:
    """One points entry of the refbox's ledger."""

    team: str
    phase: str
    points: int
    reason: str
    game_time: float
    machine: str | None = None
    order: int | None = None


@dataclass(frozen=True)
class StationTruth:
    """A station as it really is: ``zone`` number, ``rotation`` degrees,
    ``pose`` of its centre, ``state`` its production state, ``light`` the
    lights it shows in exploration (2016: the colours of its type's light
    code, sorted; empty where the profile has none)."""

    name: str
    team: str
    zone: int
    rotation: int
    pose: Pose2D
    state: str = "IDLE"
    light: tuple[str, ...] = ()

    def reported(self, properties) -> dict:
        """The true values of the exploration report's ``properties``
        (``zone``, ``light``, ``orientation``) as the team server's snapshot
        gives them under ``known``."""
        values = {"zone": self.zone, "light": tuple(sorted(self.light)), "orientation": self.rotation}
        return {p: values[p] for p in properties}


@dataclass(frozen=True)
class Delivery:
    team: str
    game_time: float
    points: int
    order: int | None
    how: str


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


class TeamServerHandle(abc.ABC):
    """An in-process team server (see the module doc)."""

    @abc.abstractmethod
    def tick(self) -> None:
        """One step: read both links, decide, send.  Never blocks."""

    @abc.abstractmethod
    def restart(self) -> None:
        """Kill the server without a goodbye and start a new one on the same
        state database and a fresh agent listener."""

    @abc.abstractmethod
    def snapshot(self) -> dict:
        """Plain-data view for reports: ``robots`` {number: {"task": kind or
        None, "task_id", "status"}}, ``tasks`` [{"id", "kind", "state",
        "robot", "machine", "assigned_at", "finished_at"}], ``known``
        {machine: {property: value}} of the report's properties (zone and
        light in 2016, zone and orientation from 2017) the server is sure of
        (its own reporting confidence), lights as sorted colour tuples, ``stations`` {machine: state as the
        server last heard it} and ``delivered`` (products delivered)."""

    def close(self) -> None:
        pass


@dataclass
class TeamServerOptions:
    """Tuning passed to a team-server factory: ``baseline`` selects the greedy
    one-order-at-a-time production instead of the HTN planner;
    ``map_period`` how often (s) a changed machine map goes to the robots."""

    baseline: bool = False
    map_period: float = 5.0
    extra: dict = field(default_factory=dict)


SimulatorFactory = Callable[..., Simulation]
TeamServerFactory = Callable[..., TeamServerHandle]


def load_simulator(name: str) -> SimulatorFactory:
    """The ``rll_bt.simulators`` entry point ``name``; KeyError names the installed ones."""
    from .. import plugins
    return plugins.load(SIMULATORS, name)


def load_teamserver(name: str) -> TeamServerFactory:
    """The ``rll_bt.teamservers`` entry point ``name``; KeyError names the installed ones."""
    from .. import plugins
    return plugins.load(TEAMSERVERS, name)
