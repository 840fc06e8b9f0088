"""The refbox's clock follows the world's: SimTimeSync on its TCP port.

A refbox started with ``llsfrb/simulation/enable: true`` and
``llsfrb/simulation/time-sync/enable: true`` takes its time from the
SimTimeSync messages (COMP_ID 2000, MSG_TYPE 327: ``sim_time``,
``real_time_factor``, ``paused``) it receives on its TCP stream (port
4444, never encrypted).  Its game clock then advances by the differences
of ``sim_time`` times ``llsfrb/simulation/speedup`` (keep that at 1.0), and
with ``time-sync/estimate-time: true`` it extrapolates between messages
with ``real_time_factor`` and never goes back, so it gains on a world that
stalls (seen: 86 s ahead after 8 minutes on a loaded machine); with
``false`` (what docs/league.md configures) its time is the last message's.  Send from before the game is RUNNING on: the
refbox takes the first game-time step from the last time it saw.

:class:`TimeSync` is called from the world's loop with the world's time; it
sends at most every ``period`` world seconds, and at once when ``paused``
changes.
"""
from __future__ import annotations

import time


def split_time(t: float) -> tuple[int, int]:
    """Seconds as (sec, nsec), nsec in 0..999 999 999."""
    sec = int(t // 1)
    nsec = int(round((t - sec) * 1e9))
    if nsec >= 1_000_000_000:
        sec, nsec = sec + 1, nsec - 1_000_000_000
    return sec, nsec


class TimeSync:
    """Send the world's time to the refbox at ``host``:``port``.

    ``profile``: the refbox's message set ("rcll2025" or "rcll2016", both
    have SimTimeSync).  ``period``: world seconds between messages.
    ``real_time_factor``: None to measure it (world seconds per wall second
    since the last message), or a fixed value.  ``sent`` counts messages."""

    def __init__(self, host: str = "127.0.0.1", port: int = 4444, *, profile: str = "rcll2025",
                 period: float = 0.1, real_time_factor: float | None = None, transport=None):
        from rll_bt import msgs
        from rll_bt.comm import MessageRegistry, StreamClient
        self.ms = msgs.message_set(profile)
        self.period = float(period)
        self.fixed_rtf = real_time_factor
        self.link = transport or StreamClient(host, int(port), registry=MessageRegistry.from_message_set(self.ms),
                                              channel="refbox-stream")
        self.sent = 0
        self._last: tuple[float, float] | None = None        # (world time, wall time) of the last message
        self._paused: bool | None = None
        self.rtf = 1.0

    def wait_connected(self, timeout: float) -> bool:
        return self.link.wait_connected(timeout)

    def update(self, sim_time: float, paused: bool = False) -> bool:
        """Call after each world step; True when a message went out."""
        wall = time.monotonic()
        due = (self._last is None or paused != self._paused
               or sim_time - self._last[0] >= self.period - 1e-9)
        if not due:
            return False
        if self.fixed_rtf is not None:
            self.rtf = float(self.fixed_rtf)
        elif self._last is not None and wall > self._last[1]:
            self.rtf = 0.0 if paused else (sim_time - self._last[0]) / (wall - self._last[1])
        sec, nsec = split_time(sim_time)
        msg = self.ms.SimTimeSync(sim_time=self.ms.get("Time")(sec=sec, nsec=nsec),
                                  real_time_factor=self.rtf, paused=bool(paused))
        ok = self.link.send(msg)
        self.link.wait(0.0)                                   # push the frame out
        if ok:
            self.sent += 1
            self._last, self._paused = (sim_time, wall), paused
        return ok

    def close(self) -> None:
        self.link.close()


__all__ = ["TimeSync", "split_time"]
