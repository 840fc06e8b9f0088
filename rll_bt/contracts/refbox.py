"""The refbox-view contract: what a game reads of the referee box.

:class:`RefboxView` is the game as the refbox keeps it: state and points
(:class:`GameStatus`), the ledger (:class:`Award`, :class:`Delivery`),
the stations as they really are (:class:`StationTruth`) and the orders.
A simulator's refbox answers it (:class:`SimulatedRefbox` adds what the
host of a simulated game does with its refbox); so can a view built from
what a real refbox broadcasts.

Times are seconds of the game's clock unless named *game time* (the
refbox's seconds into the current phase).  Poses are field-frame metres and
radians of the rules profile.
"""
from __future__ import annotations

import abc
from dataclasses import dataclass, field
from pathlib import Path

from ..backend.types import Pose2D


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


@dataclass(frozen=True)
class Tally:
    """What a game report counts of one team beside its points: its stations that went
    BROKEN, by cause (the refbox's reason as a short key, e.g. "not-prepared",
    "timeout"), and the referee calls the refbox leaves to a human referee (what ->
    {"count": n, "penalty": the rulebook's points, not taken off the score})."""

    broken: dict[str, int] = field(default_factory=dict)
    referee: dict[str, dict] = field(default_factory=dict)

    @property
    def broken_total(self) -> int:
        return sum(self.broken.values())

    @property
    def referee_penalty(self) -> int:
        return sum(int(c.get("penalty") or 0) for c in self.referee.values())


class RefboxView(abc.ABC):
    """The referee box's game, read-only (see the module doc)."""

    @abc.abstractmethod
    def status(self) -> GameStatus:
        """Phase, state, game time and points now."""

    @abc.abstractmethod
    def awards(self) -> list[Award]:
        """Every points entry so far, in order."""

    @abc.abstractmethod
    def deliveries(self) -> list[Delivery]:
        """Every delivery so far, in order."""

    @abc.abstractmethod
    def stations(self) -> dict[str, StationTruth]:
        """Every station of the game by name, as it really is."""

    def orders(self) -> list[dict]:
        """The game's orders as plain dicts (id, complexity, quantity, window)."""
        return []

    def tally(self, team: str) -> Tally:
        """``team``'s stations gone BROKEN and referee calls (empty where unknown)."""
        return Tally()


class SimulatedRefbox(RefboxView):
    """A refbox a simulated game hosts: the view, and what its operator does."""

    @abc.abstractmethod
    def start(self) -> None:
        """Start the game (the operator's RUNNING)."""

    @abc.abstractmethod
    def step(self) -> None:
        """The refbox's turn: it receives, ticks its game and sends what is due
        (:class:`RefboxProcess`: the refbox process's calls on the world are served)."""

    def station_down(self, machine: str, seconds: float) -> None:
        """Take a station DOWN now for ``seconds`` of game time (a fault)."""
        raise NotImplementedError(f"{type(self).__name__} cannot take a station down")

    def close(self) -> None:
        pass


class InProcessRefbox(SimulatedRefbox):
    """The refbox in the game's own process, on the world's clock."""

    @abc.abstractmethod
    def attach_bus(self, bus) -> None:
        """Put the refbox on an in-process :class:`rll_bt.comm.Bus`: channels
        "public", "cyan", "magenta" and the control stream at "refbox"."""

    def attach_udp(self, *, host: str, layout, stream_port: int = -1) -> None:
        """Put the refbox on UDP on the world's clock (sending to ``host`` on
        ``layout``, the refbox's view): teams of other processes play in this
        world (``rll-bt sim --external-team``).  Optional."""
        raise NotImplementedError(f"{type(self).__name__} cannot talk UDP")


class RefboxProcess(SimulatedRefbox):
    """A refbox that runs as a process of its own (``rll-bt sim --processes``),
    driving the world's stations over a link the world serves."""

    @abc.abstractmethod
    def command(self, *, host: str, layout, snapshot: Path, message_log: Path | None = None) -> list[str]:
        """The ``rll-bt`` arguments of the refbox process: on UDP sending to
        ``host`` on ``layout`` (a :class:`rll_bt.comm.Layout`, the refbox's
        view), rewriting the ``snapshot`` file this view is read from, and
        logging every message it sends and receives to ``message_log``
        (JSON lines of :mod:`rll_bt.comm.msglog`, on the monotonic wall clock)."""

    def ready(self) -> bool:
        """Whether the process is up (it wrote its first snapshot)."""
        return True
