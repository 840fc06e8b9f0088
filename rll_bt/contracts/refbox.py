"""What a game reads of the referee box: its state, its ledger, the stations.

Times are seconds of the simulation clock unless named *game time* (the
refbox's seconds into the current phase).  Poses are field-frame metres and
radians of the rules profile.
"""
from __future__ import annotations

from dataclasses import dataclass

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

