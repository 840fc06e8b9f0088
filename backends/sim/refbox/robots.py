"""The robot registry the refbox keeps from BeaconSignals.

Robots are keyed by (number, team name), as the refbox does.  ``last_seen``
and the timeouts are clock seconds (not game seconds): a robot that sent no
beacon for 5 s is reported lost once, and dropped after 1080 s.  Robots of a
team name the game does not know are kept without a colour and left out of
RobotInfo, as the refbox does.
"""
from __future__ import annotations

from dataclasses import dataclass

LOST_AFTER = 5.0        # PEER-LOST-TIMEOUT
REMOVE_AFTER = 1080.0   # PEER-REMOVE-TIMEOUT


@dataclass
class Robot:
    number: int
    team: str                     # team name as sent
    name: str                     # peer name
    team_color: str | None        # CYAN / MAGENTA / None for an unknown team
    host: str
    first_seen: float             # clock seconds
    last_seen: float              # clock seconds
    last_seen_epoch: float        # Unix seconds (for RobotInfo.last_seen)
    pose: tuple[float, float, float] | None = None   # x, y (m), ori (rad), field frame
    lost: bool = False
    beacons: int = 0
    state: str = "ACTIVE"


class RobotRegistry:
    def __init__(self, lost_after: float = LOST_AFTER, remove_after: float = REMOVE_AFTER):
        self.lost_after, self.remove_after = lost_after, remove_after
        self.robots: dict[tuple[int, str], Robot] = {}

    def beacon(self, *, number: int, team: str, name: str, team_color: str | None, host: str,
               now: float, epoch: float, pose=None) -> tuple[Robot, str | None]:
        """Record a beacon; returns the robot and "new", "back" (after lost) or None."""
        key = (int(number), team)
        r = self.robots.get(key)
        what = None
        if r is None:
            r = Robot(int(number), team, name, team_color, host, now, now, epoch)
            self.robots[key] = r
            what = "new"
        elif r.lost:
            what = "back"
        r.name, r.host, r.last_seen, r.last_seen_epoch = name, host, now, epoch
        r.team_color = team_color
        r.lost = False
        r.beacons += 1
        if pose is not None:
            r.pose = pose
        return r, what

    def check(self, now: float) -> tuple[list[Robot], list[Robot]]:
        """Mark robots silent for ``lost_after`` s as lost and drop those silent for
        ``remove_after`` s; returns (newly lost, removed)."""
        lost, removed = [], []
        for key, r in list(self.robots.items()):
            silent = now - r.last_seen
            if silent >= self.remove_after:
                removed.append(self.robots.pop(key))
            elif silent >= self.lost_after and not r.lost:
                r.lost = True
                lost.append(r)
        return lost, removed

    def listed(self) -> list[Robot]:
        """Robots with a team colour, by colour and number (RobotInfo)."""
        return sorted((r for r in self.robots.values() if r.team_color),
                      key=lambda r: (r.team_color, r.number))

    def __len__(self) -> int:
        return len(self.robots)
