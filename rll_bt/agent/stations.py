"""Our stations' states as the refbox tells every robot of the team.

The refbox sends MachineInfo on the team's encrypted channel (0.5-2 s
apart and on every state change); the agent keeps the last state of each
station here, as the service ``refbox_stations`` of its trees, so that a
robot can wait at a station until the refbox shows it PREPARED before it
puts a workpiece on the input (the 2016 refbox breaks a station fed while
not prepared; today's counts the time from the prepare).
"""
from __future__ import annotations


class StationStates:
    """``state(name)``: the station's last reported state, None before any MachineInfo
    named it; ``since(name)``: the clock time it entered that state (as heard);
    ``heard``: whether any MachineInfo arrived at all.  ``waiting``: the station the
    robot waits at, docked, for its prepare (the ``wait_station`` node sets it; the
    agent's RobotStatus says it as ``waiting_at``, so that a team server can prepare
    the station just then), None otherwise."""

    def __init__(self):
        self._states: dict[str, tuple[str, float]] = {}
        self.heard = False
        self.waiting: str | None = None

    def update(self, msg, now: float) -> list[str]:
        """Take one MachineInfo; returns the stations whose state changed."""
        changed = []
        for m in msg.machines:
            old = self._states.get(m.name)
            if old is None or old[0] != m.state:
                self._states[m.name] = (m.state, now)
                changed.append(m.name)
        self.heard = True
        return changed

    def state(self, name: str) -> str | None:
        got = self._states.get(name)
        return got[0] if got else None

    def since(self, name: str) -> float | None:
        got = self._states.get(name)
        return got[1] if got else None
