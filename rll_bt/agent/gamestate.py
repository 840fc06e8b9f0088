"""May the robot move?  The game state from the refbox and the team server.

Robots must stand still unless the refbox's state is RUNNING and the phase
is neither PRE_GAME nor POST_GAME.  Two sources say so: the refbox's
``GameState`` on the public channel (authoritative) and the team server's
forwarded ``GamePhase``.  A refbox GameState younger than ``fresh``
seconds wins; otherwise the latest of either counts.  Until either has
spoken the robot stands still (unless ``require`` is False).

Both messages use the same numbers for state (INIT 0, WAIT_START 1,
RUNNING 2, PAUSED 3) and phase (PRE_GAME 0, SETUP 10, EXPLORATION 20,
PRODUCTION 30, POST_GAME 40).  GameState also names the teams, which is how
the agent learns its colour when it was not given one; the refbox's word on
the colour outranks the team server's.
"""
from __future__ import annotations

from dataclasses import dataclass

from ..clock import Clock

RUNNING = 2
STATES = {0: "INIT", 1: "WAIT_START", 2: "RUNNING", 3: "PAUSED"}
PHASES = {0: "PRE_GAME", 10: "SETUP", 20: "EXPLORATION", 30: "PRODUCTION", 40: "POST_GAME"}
STILL_PHASES = (0, 40)


@dataclass(frozen=True)
class GameView:
    state: int
    phase: int
    game_time: float
    received: float         # agent clock time of receipt
    source: str             # "refbox" or "teamserver"

    @property
    def moving_allowed(self) -> bool:
        return self.state == RUNNING and self.phase not in STILL_PHASES

    def describe(self) -> str:
        return f"{STATES.get(self.state, self.state)}/{PHASES.get(self.phase, self.phase)} ({self.source})"


class GameGate:
    def __init__(self, team_name: str, clock: Clock, fresh: float = 3.0, require: bool = True):
        self.team_name = team_name
        self.clock = clock
        self.fresh = fresh
        self.require = require
        self.refbox: GameView | None = None
        self.server: GameView | None = None
        self.refbox_color: str | None = None    # from GameState's team names
        self.server_color: str | None = None    # from GamePhase.team_color

    @property
    def color(self) -> str | None:
        """Our colour, "CYAN"/"MAGENTA": the refbox's word first, else the team server's."""
        return self.refbox_color or self.server_color

    def on_game_state(self, msg) -> str | None:
        """A refbox GameState; returns our colour if it names our team."""
        self.refbox = GameView(int(msg.state), int(msg.phase), _seconds(msg.game_time), self.clock.now(), "refbox")
        if getattr(msg, "team_cyan", "") == self.team_name:
            self.refbox_color = "CYAN"
        elif getattr(msg, "team_magenta", "") == self.team_name:
            self.refbox_color = "MAGENTA"
        return self.color

    def on_game_phase(self, msg) -> str | None:
        """The team server's GamePhase; returns the colour it names, if any."""
        self.server = GameView(int(msg.state), int(msg.phase), float(msg.game_time), self.clock.now(),
                               "teamserver")
        if msg.HasField("team_color"):
            self.server_color = ("CYAN", "MAGENTA")[int(msg.team_color)]
        return self.color

    @property
    def view(self) -> GameView | None:
        """The game state that counts now (None: nothing heard yet)."""
        rb, sv = self.refbox, self.server
        if rb is not None and self.clock.now() - rb.received <= self.fresh:
            return rb
        if rb is None or (sv is not None and sv.received > rb.received):
            return sv if sv is not None else rb
        return rb

    @property
    def moving_allowed(self) -> bool:
        v = self.view
        if v is None:
            return not self.require
        return v.moving_allowed

    def describe(self) -> str:
        v = self.view
        return "no game state yet" if v is None else v.describe()


def _seconds(t) -> float:
    """llsf_msgs.Time -> seconds."""
    return float(t.sec) + float(t.nsec) * 1e-9
