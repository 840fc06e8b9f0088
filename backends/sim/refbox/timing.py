"""Phase lengths and the game-time scale of a simulated game.

All lengths are game seconds.  ``exploration`` is the length of an
EXPLORATION phase (2016); rules that explore inside PRODUCTION (2022+) have
none and set ``exploration_in_production`` instead, the first seconds of
PRODUCTION during which machines are reported (``exploration_time`` is
whichever applies).  ``speed`` scales game time against the
clock: with ``speed=10`` one clock second is ten game seconds (phases,
processing, down periods and order windows all run ten times faster), while
network periods and the robot-lost timeout stay in clock seconds, because
the teams' software does not speed up.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, replace

PRE_GAME, SETUP, EXPLORATION, PRODUCTION, POST_GAME = (
    "PRE_GAME", "SETUP", "EXPLORATION", "PRODUCTION", "POST_GAME")
PHASES = (PRE_GAME, SETUP, EXPLORATION, PRODUCTION, POST_GAME)
INIT, WAIT_START, RUNNING, PAUSED = "INIT", "WAIT_START", "RUNNING", "PAUSED"
STATES = (INIT, WAIT_START, RUNNING, PAUSED)

_OVERRIDABLE = ("setup", "exploration", "production", "overtime")


@dataclass(frozen=True)
class Timing:
    """Phase lengths in game seconds and the game-time ``speed`` factor."""

    setup: float
    exploration: float
    production: float
    overtime: float
    speed: float = 1.0
    exploration_in_production: float = 0.0
    nominal_production: float = 900.0     # the rules' production length (scales windows)

    def __post_init__(self):
        for name in _OVERRIDABLE + ("exploration_in_production", "nominal_production"):
            v = getattr(self, name)
            if not (isinstance(v, (int, float)) and math.isfinite(v) and v >= 0):
                raise ValueError(f"phase length {name}={v!r} must be a number >= 0 seconds")
        if not (math.isfinite(self.speed) and self.speed > 0):
            raise ValueError(f"speed {self.speed!r} must be > 0")

    @classmethod
    def from_profile(cls, profile, *, speed: float = 1.0, **overrides: float) -> Timing:
        """The profile's phase lengths, with ``overrides`` (setup=, exploration=,
        production=, overtime=) replacing single values.  For a profile that
        explores inside PRODUCTION, ``exploration=`` sets that window."""
        bad = set(overrides) - set(_OVERRIDABLE)
        if bad:
            raise ValueError(f"unknown phase {', '.join(sorted(bad))} "
                             f"(known: {', '.join(_OVERRIDABLE)})")
        p = profile.phases
        t = cls(setup=p.setup, exploration=p.exploration, production=p.production,
                overtime=p.overtime, speed=speed,
                exploration_in_production=p.exploration_in_production,
                nominal_production=p.production or 900.0)
        values = {k: float(v) for k, v in overrides.items()}
        if p.exploration_in_production > 0 and "exploration" in values:
            values["exploration_in_production"] = values.pop("exploration")
        return replace(t, **values)

    def length(self, phase: str) -> float | None:
        """Length of ``phase`` without overtime, None for phases without an end."""
        return {SETUP: self.setup, EXPLORATION: self.exploration,
                PRODUCTION: self.production}.get(phase)

    @property
    def exploration_time(self) -> float:
        """Seconds of exploration, in its own phase or at the start of PRODUCTION."""
        return self.exploration or self.exploration_in_production

    @property
    def production_scale(self) -> float:
        """This production length over the rules' (900 s in 2016, 1200 s in 2025; 1.0 for
        the real game); order windows and down periods shrink with it so a short test
        game stays playable."""
        if self.production <= 0 or self.nominal_production <= 0:
            return 1.0
        return self.production / self.nominal_production


def parse_phase_lengths(text: str) -> dict[str, float]:
    """``"setup=10,exploration=60,production=120"`` -> dict of seconds.

    Raises ValueError naming the bad item.
    """
    out: dict[str, float] = {}
    for item in filter(None, (s.strip() for s in text.split(","))):
        name, sep, value = item.partition("=")
        name = name.strip().lower()
        if not sep or name not in _OVERRIDABLE:
            raise ValueError(f"bad phase length {item!r}: expected NAME=SECONDS with NAME one of "
                             f"{', '.join(_OVERRIDABLE)}")
        try:
            seconds = float(value)
        except ValueError:
            raise ValueError(f"bad phase length {item!r}: {value.strip()!r} is not a number") from None
        if not math.isfinite(seconds) or seconds < 0:
            raise ValueError(f"bad phase length {item!r}: seconds must be >= 0")
        out[name] = seconds
    return out
