"""The world's pace in a process game: how far the world steps after each moment of serving calls.

Everything in a process game runs on the wall clock: the world advances by the wall time that passed,
at most 0.1 s a step, so on a loaded machine it may fall behind.  The refbox's game clock is the world's
time, pushed over the station link after each step: a world fallen behind the wall clock holds the game's
time with it (before, the refbox kept the wall clock and such a game lost the seconds the world did not
play).  A hardware game (``--hardware emulated``) catches up instead of dropping the time it fell behind,
since its devices (an emulated base's motors) moved all that time (``ProcessGame.catch_up``).
"""
from __future__ import annotations


def world_advance(last: float, now: float, longest: float, catch_up: float | None) -> tuple[float, float]:
    """How far to step a world that stands at wall time ``last`` at wall time ``now``: (seconds to step,
    the wall time it then stands at).  A step covers at most ``longest``.  Without ``catch_up`` the rest of
    the wall time passed is dropped (the world falls behind for good: right when everything that moves
    lives in the world).  With it, the world stands at ``last + step`` and the next steps catch up, as
    long as it is less than ``catch_up`` behind (what is more is dropped): devices that run on the wall
    clock (an emulated base's motors) moved all that time, and the world must move with them."""
    if catch_up is None:
        return min(now - last, longest), now
    last = max(last, now - catch_up)
    step = min(now - last, longest)
    return step, last + step


class WorldLag:
    """How far a hardware game's world stood behind the wall clock, measured at every tick: the longest
    lag, and the wall seconds (and spells) it stood more than ``stale`` behind.  A world that far behind
    casts and renders nothing (backends/sim/hardware_parts.STALE_CAST): its lasers resend their last
    scan and its cameras go silent, which the agents see as a lost camera after 3 s.  A game over whose
    end the world had caught up says nothing of that at its end; this says how much of it there was."""

    def __init__(self, stale: float):
        self.stale = stale
        self.longest = 0.0
        self.stale_seconds = 0.0
        self.stale_spells = 0
        self._prev: float | None = None
        self._was_stale = False

    def add(self, now: float, stands_at: float) -> None:
        """A tick at wall time ``now`` left the world standing at wall time ``stands_at``."""
        behind = max(now - stands_at, 0.0)
        self.longest = max(self.longest, behind)
        stale = behind > self.stale
        if stale and self._prev is not None:
            self.stale_seconds += now - self._prev
        if stale and not self._was_stale:
            self.stale_spells += 1
        self._was_stale = stale
        self._prev = now

    def summary(self) -> dict:
        return {"longest_s": round(self.longest, 3), "stale_s": round(self.stale_seconds, 1),
                "stale_spells": self.stale_spells, "stale_above_s": self.stale}
