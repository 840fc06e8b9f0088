"""What one robot agent is: its identity and its timing.

All periods and timeouts are seconds of the agent's clock (the wall clock
in real games, the simulated clock in lockstep runs).
"""
from __future__ import annotations

import re
from dataclasses import dataclass, field
from pathlib import Path

from ..rules import PROFILES

COLORS = ("CYAN", "MAGENTA")
_KEY_OK = re.compile(r"[\x21-\x7e]+$")   # printable ASCII, no blanks


def check_team_key(key: str) -> str:
    """The team key as the refbox takes it: 1..256 printable ASCII characters
    without blanks (``llsfrb/game/crypto-keys/<team>``).  ValueError otherwise."""
    if not isinstance(key, str) or not key:
        raise ValueError("the team key is empty")
    if len(key) > 256:
        raise ValueError(f"the team key is {len(key)} characters long (at most 256)")
    if not _KEY_OK.match(key):
        raise ValueError("the team key must be printable ASCII without spaces, tabs or line breaks")
    return key


def normalise_color(color: str | None) -> str | None:
    """"cyan"/"CYAN"/0 -> "CYAN", "magenta"/1 -> "MAGENTA", None -> None."""
    if color is None:
        return None
    if isinstance(color, int):
        return COLORS[color]
    c = str(color).upper()
    if c not in COLORS:
        raise ValueError(f"unknown team colour {color!r} (cyan or magenta)")
    return c


@dataclass
class AgentConfig:
    """One robot's agent.

    - ``robot_id``: jersey number (1..), as in BeaconSignal.number
    - ``team_name``: exactly as configured in the refbox
    - ``peer_name``: robot name (default ``R<robot_id>``)
    - ``profile``: rules profile, "rcll2016" or "rcll2025"
    - ``color``: team colour if known in advance ("CYAN"/"MAGENTA"); else
      learnt from the refbox's GameState or the team server's GamePhase
    - ``trees_dir``: where ``<task kind>.yaml`` live (None: the installed ``trees/``)
    - ``hz``: tree tick rate
    - ``heartbeat_period``, ``status_period``, ``beacon_period``: seconds
    - ``server_timeout``: seconds without anything from the team server
      after which it counts as silent (the status says so; the link keeps
      reconnecting on its own)
    - ``game_state_fresh``: seconds a refbox GameState outranks the team
      server's forwarded GamePhase
    - ``require_game``: stand still until a game state says RUNNING (set
      False only for bench tests without refbox and team server game state)
    - ``capabilities``: announced in RobotHello
    - ``league_only``: the team server speaks only the league's messages
      (AgentTask, BeaconSignal): send it nothing else, do not take its
      silence for a lost link, and find the stations without its machine
      map (from the refbox's MachineInfo and the robot's own sightings)
    - ``beacon_finished``: how many of the last finished tasks every
      BeaconSignal lists (field 10)
    """
    robot_id: int
    team_name: str
    peer_name: str = ""
    profile: str = "rcll2016"
    color: str | None = None
    trees_dir: Path | None = None
    hz: float = 10.0
    heartbeat_period: float = 1.0
    status_period: float = 1.0
    beacon_period: float = 1.0
    server_timeout: float = 5.0
    game_state_fresh: float = 3.0
    require_game: bool = True
    capabilities: tuple[str, ...] = ("explore", "grip", "shelf")
    league_only: bool = False
    beacon_finished: int = 16
    extra: dict = field(default_factory=dict)

    def __post_init__(self) -> None:
        if int(self.robot_id) < 1:
            raise ValueError(f"robot_id must be 1 or more, not {self.robot_id}")
        self.robot_id = int(self.robot_id)
        if not self.team_name:
            raise ValueError("team_name is empty")
        if not self.peer_name:
            self.peer_name = f"R{self.robot_id}"
        if self.profile not in PROFILES:
            raise ValueError(f"unknown rules profile {self.profile!r} (known: {', '.join(PROFILES)})")
        self.color = normalise_color(self.color)
        if self.hz <= 0:
            raise ValueError(f"hz must be positive, not {self.hz}")
        for name in ("heartbeat_period", "status_period", "beacon_period", "server_timeout"):
            if getattr(self, name) <= 0:
                raise ValueError(f"{name} must be positive, not {getattr(self, name)}")
        if self.trees_dir is not None:
            self.trees_dir = Path(self.trees_dir)

    @property
    def tick_period(self) -> float:
        return 1.0 / self.hz
