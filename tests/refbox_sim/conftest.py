"""Fixtures for the simulated refbox: a game on a simulated clock and an in-memory world."""
from __future__ import annotations

import pytest

from backends.sim.refbox import RefboxGame, Timing
from rll_bt.clock import SimClock
from rll_bt.rules import profile


class Harness:
    """A game between "Caro" (cyan) and "Grips" (magenta) on a SimClock; 2016 rules
    unless ``rules="rcll2025"`` (then ``exploration`` is the reporting time in PRODUCTION,
    180 s by default, and production 1200 s)."""

    def __init__(self, seed: int = 1, teams=("Caro", "Grips"), config=None, speed: float = 1.0,
                 rules: str = "rcll2016", **phases):
        if rules == "rcll2016":
            lengths = {"setup": 5.0, "exploration": 30.0, "production": 900.0, **phases}
        else:
            lengths = {"setup": 5.0, **phases}
        self.clock = SimClock()
        self.timing = Timing.from_profile(profile(rules), speed=speed, **lengths)
        self.game = RefboxGame(rules, self.clock, seed=seed, team_cyan=teams[0],
                               team_magenta=teams[1], timing=self.timing, config=config)
        self.world = self.game.world

    def run(self, seconds: float, dt: float = 0.25) -> None:
        """Advance the clock by ``seconds`` in steps of ``dt``, ticking the game."""
        n = int(round(seconds / dt))
        for _ in range(n):
            self.clock.advance(dt)
            self.game.tick()

    def exploration(self) -> "Harness":
        self.game.start()
        self.game.set_phase("EXPLORATION")
        return self

    def production(self) -> "Harness":
        self.game.start()
        self.game.set_phase("PRODUCTION")
        return self

    def awards(self, team: str, phase: str | None = None):
        return [e for e in self.game.ledger.for_team(team) if phase in (None, e.phase)]

    def award_sum(self, team: str, phase: str | None = None) -> int:
        return sum(e.points for e in self.awards(team, phase))

    def events(self, kind: str):
        return [e for e in self.game.events if e.kind == kind]

    def attention(self, team=...):
        return [e.text for e in self.events("attention") if team is ... or e.team == team]

    def station(self, name: str):
        return self.game.stations[name]


@pytest.fixture
def harness():
    """Factory: ``harness(seed=..., production=..., config=...)`` -> :class:`Harness`."""
    return Harness


@pytest.fixture
def harness25():
    """Factory of 2025 games: ``harness25(seed=..., exploration=..., production=...)``."""
    return lambda **kw: Harness(rules="rcll2025", **kw)
