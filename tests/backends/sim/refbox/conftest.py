"""Fixtures for the simulated refbox: a game on a simulated clock and an in-memory world,
and a scripted robot on the in-process bus."""
from __future__ import annotations

from collections import defaultdict

import pytest

from backends.sim.refbox import RefboxGame, Timing
from backends.sim.refbox.messages import set_enum
from rll_bt.clock import SimClock
from rll_bt.comm import MessageRegistry
from rll_bt.rules import profile


class Harness:
    """A game between "Caro" (cyan) and "Grips" (magenta) on a SimClock; 2016 rules
    unless ``rules="rcll2025"`` (then ``exploration`` is the reporting time in PRODUCTION,
    180 s by default, and production 1200 s)."""

    def __init__(self, seed: int = 1, teams=("Caro", "Grips"), config=None, speed: float = 1.0,
                 rules: str = "rcll2016", mockup: bool = False, **phases):
        if rules == "rcll2016":
            lengths = {"setup": 5.0, "exploration": 30.0, "production": 900.0, **phases}
        else:
            lengths = {"setup": 5.0, **phases}
        self.clock = SimClock()
        self.timing = Timing.from_profile(profile(rules), speed=speed, **lengths)
        self.game = RefboxGame(rules, self.clock, seed=seed, team_cyan=teams[0],
                               team_magenta=teams[1], timing=self.timing, config=config,
                               mockup=mockup)
        self.world = self.game.world

    def run(self, seconds: float, dt: float = 0.25) -> None:
        """Advance the clock by ``seconds`` in steps of ``dt``, ticking the game."""
        n = int(round(seconds / dt))
        for _ in range(n):
            self.clock.advance(dt)
            self.game.tick()

    def exploration(self) -> Harness:
        self.game.start()
        self.game.set_phase("EXPLORATION")
        return self

    def production(self) -> Harness:
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


class BusTeam:
    """A scripted robot of ``team_name``: listens on the public bus channel and its team
    ``channel`` (encrypted with ``key``), keeps what arrived by (channel, type)."""

    def __init__(self, bus, message_set, key, channel="cyan", team_name="Caro", number=2):
        self.ms = message_set
        reg = MessageRegistry.from_message_set(message_set)
        self.public = bus.peer("public", registry=reg, name="robot-public")
        self.team = bus.peer(channel, registry=reg, key=key, name=f"robot-{channel}")
        self.color = channel.upper()
        self.team_name, self.number = team_name, number
        self.got = defaultdict(list)          # (channel, type) -> messages
        self.seq = 0

    def poll(self):
        for rec in self.public.receive():
            self.got[("public", rec.type_name)].append(rec.msg)
        for rec in self.team.receive():
            self.got[("team", rec.type_name)].append(rec.msg)

    def last(self, channel, name):
        items = self.got[(channel, name)]
        return items[-1] if items else None

    def beacon(self, clock):
        b = self.ms.BeaconSignal()
        b.time.sec, b.time.nsec = int(clock.epoch()), 0
        self.seq += 1
        b.seq, b.number, b.team_name, b.peer_name = self.seq, self.number, self.team_name, "R2"
        set_enum(b, "team_color", self.color)
        b.pose.timestamp.sec, b.pose.timestamp.nsec = int(clock.epoch()), 0
        b.pose.x, b.pose.y, b.pose.ori = 1.5, 0.5, 0.0
        self.team.send(b)


@pytest.fixture
def bus_team():
    """The :class:`BusTeam` class: ``bus_team(bus, message_set, key, channel=...)``."""
    return BusTeam
