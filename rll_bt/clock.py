"""Clocks.  Every component takes one; none calls ``time.time()`` itself.

``now()`` is monotonic seconds used for timeouts and periods; ``epoch()`` is
Unix time in seconds, used where a message carries a wall time (a beacon's
``time`` field).  :class:`SimClock` advances only when told to, so a lockstep
simulation is deterministic and as fast as the CPU allows.
"""
from __future__ import annotations

import threading
import time
from typing import Protocol, runtime_checkable


@runtime_checkable
class Clock(Protocol):
    def now(self) -> float:
        """Monotonic seconds."""

    def epoch(self) -> float:
        """Unix time in seconds."""

    def sleep(self, seconds: float) -> None:
        """Wait ``seconds`` of this clock's time."""


class WallClock:
    """The machine's clock."""

    def now(self) -> float:
        return time.monotonic()

    def epoch(self) -> float:
        return time.time()

    def sleep(self, seconds: float) -> None:
        if seconds > 0:
            time.sleep(seconds)


class SimClock:
    """A simulated clock that moves only through :meth:`advance`.

    ``sleep`` from another thread blocks until the owner has advanced the
    clock far enough; from the thread that owns the clock it simply advances.
    """

    def __init__(self, start: float = 0.0, epoch_offset: float = 1_700_000_000.0):
        self._t = float(start)
        self._epoch_offset = float(epoch_offset)
        self._cond = threading.Condition()
        self._owner = threading.get_ident()

    def now(self) -> float:
        return self._t

    def epoch(self) -> float:
        return self._epoch_offset + self._t

    def sync_epoch(self, epoch: float) -> None:
        """From now on :meth:`epoch` reads ``epoch`` at the current time (a
        simulation that follows the wall clock stamps its messages with real
        Unix time)."""
        self._epoch_offset = float(epoch) - self._t

    def advance(self, seconds: float) -> float:
        if seconds < 0:
            raise ValueError(f"cannot advance a clock backwards ({seconds})")
        with self._cond:
            self._t += seconds
            self._cond.notify_all()
        return self._t

    def set(self, t: float) -> None:
        if t < self._t:
            raise ValueError(f"cannot set the clock back from {self._t} to {t}")
        self.advance(t - self._t)

    def sleep(self, seconds: float) -> None:
        if seconds <= 0:
            return
        if threading.get_ident() == self._owner:
            self.advance(seconds)
            return
        deadline = self._t + seconds
        with self._cond:
            while self._t < deadline:
                self._cond.wait(timeout=1.0)


class SyncedClock:
    """A clock that follows another's time as it is told (a simulation's
    SimTimeSync), the way the refbox's ``time-sync`` does.

    :meth:`sync` gives the other clock's time ``t``, its speed
    (``rate``: its seconds per second of ``base``) and whether it is
    ``paused``.  Between two syncs the time runs on from the last one at
    that rate on ``base`` (the refbox's ``estimate-time``), or stands still
    while paused; before the first it runs with ``base``.  Only differences
    of the synced time count: the first sync does not jump (``now()`` is
    the synced time plus the offset it had then).  It never goes back: a
    sync behind the estimate holds the time until it catches up.
    ``epoch()`` is ``base``'s."""

    def __init__(self, base: Clock | None = None, start: float = 0.0):
        self.base = base or WallClock()
        self._t0, self._b0 = float(start), self.base.now()
        self._rate, self._paused = 1.0, False
        self._floor = float(start)
        self._offset = 0.0
        self.synced = False
        self._lock = threading.Lock()

    def sync(self, t: float, rate: float = 1.0, paused: bool = False) -> None:
        with self._lock:
            here = self._estimate()
            self._floor = max(self._floor, here)
            if not self.synced:
                self._offset = here - float(t)
            self._t0, self._b0 = float(t) + self._offset, self.base.now()
            self._rate, self._paused = max(0.0, float(rate)), bool(paused)
            self.synced = True

    def _estimate(self) -> float:
        if self._paused:
            return self._t0
        return self._t0 + (self.base.now() - self._b0) * self._rate

    def now(self) -> float:
        with self._lock:
            t = self._estimate()
            if t < self._floor:
                return self._floor
            self._floor = t
            return t

    @property
    def paused(self) -> bool:
        return self._paused

    def epoch(self) -> float:
        return self.base.epoch()

    def sleep(self, seconds: float) -> None:
        self.base.sleep(seconds)
