"""Device time stamps mapped onto the host's clock.

A scanner stamps each scan with its own counter (the URG: milliseconds
modulo 2**24; the TiM: microseconds since power-up, 32 bits).
:class:`DeviceClock` unwraps the counter and estimates the offset to the
host clock as the smallest ``receive time - device time`` seen recently:
the transfer delay only ever adds, so the minimum is the best bound, and a
window (``window`` samples) lets it follow a slowly drifting device clock.
A jump backwards of the device time (a reset, a new connection) restarts
the estimate.
"""
from __future__ import annotations

from collections import deque


class DeviceClock:
    def __init__(self, wrap: int, unit: float, window: int = 200):
        self.wrap = int(wrap)            # counter modulus
        self.unit = float(unit)          # seconds per count
        self.window = window
        self._last_raw: int | None = None
        self._epoch = 0                  # counts added by unwrapping
        self._offsets: deque = deque(maxlen=window)
        self.resets = 0

    def reset(self) -> None:
        self._last_raw = None
        self._epoch = 0
        self._offsets.clear()
        self.resets += 1

    def device_seconds(self, raw: int) -> float:
        """The unwrapped device time of counter value ``raw``."""
        raw = int(raw) % self.wrap
        if self._last_raw is not None and raw < self._last_raw:
            back = self._last_raw - raw
            if back > self.wrap // 2:      # the counter wrapped
                self._epoch += self.wrap
            else:                          # the device restarted its counter
                self._epoch = 0
                self._offsets.clear()
        self._last_raw = raw
        return (raw + self._epoch) * self.unit

    def to_host(self, raw: int, received: float) -> float:
        """Host time of a device stamp ``raw`` that arrived at ``received``."""
        device = self.device_seconds(raw)
        self._offsets.append(received - device)
        return device + min(self._offsets)
