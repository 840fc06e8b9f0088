"""Points per team and phase, as the refbox's ``points`` facts.

Every award is kept with its reason and game time.  A team's total is the
sum over phases of each phase's points floored at 0 (``game-calc-points``):
a bad exploration never eats into production points.
"""
from __future__ import annotations

from rll_bt.contracts import Award

# one award: team, phase, points (may be negative), reason, game time, machine, order
PointsEntry = Award


class Ledger:
    def __init__(self) -> None:
        self.entries: list[PointsEntry] = []

    def award(self, entry: PointsEntry) -> PointsEntry:
        self.entries.append(entry)
        return entry

    def phase_points(self, team: str, phase: str) -> int:
        """Raw (unfloored) sum of ``team``'s points in ``phase``."""
        return sum(e.points for e in self.entries if e.team == team and e.phase == phase)

    def by_phase(self, team: str) -> dict[str, int]:
        """Raw sums per phase, in the order the phases first scored."""
        out: dict[str, int] = {}
        for e in self.entries:
            if e.team == team:
                out[e.phase] = out.get(e.phase, 0) + e.points
        return out

    def total(self, team: str) -> int:
        """The score shown in GameState: per-phase sums floored at 0, added up."""
        return sum(max(0, v) for v in self.by_phase(team).values())

    def for_team(self, team: str) -> list[PointsEntry]:
        return [e for e in self.entries if e.team == team]
