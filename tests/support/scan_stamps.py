"""Scan stamps against the time the scanner measured: a source for the emulated
lasers whose scans say which they are, and the check of their stamps
(no wall-clock bounds: a loaded machine only delays, it cannot fail them)."""
import time

import numpy as np


class CountingSource:
    """An emulated scanner's ``source(t)`` whose every scan says which one it is
    (all beams at ``base + 10 * (k % 500)`` mm, ``k`` the scan's index) and was
    measured a varying while before the scanner sends it (0, 30 or 60 ms: a
    world that cast its rays earlier).  ``taken[k]`` is the host time scan ``k``
    was measured at, the time its stamp must carry."""

    def __init__(self, boot: float, period: float, beams: int, base: float = 500.0):
        self.boot, self.period, self.beams, self.base = boot, period, beams, base
        self.taken: dict[int, float] = {}

    def __call__(self, t: float):
        k = round(t / self.period)
        at = t - 0.03 * (k % 3)
        self.taken[k] = self.boot + at
        return np.full(self.beams, self.base + 10.0 * (k % 500)), at

    def index(self, ranges_m) -> int:
        """The index of the scan whose ranges are ``ranges_m`` (metres), the latest one measured."""
        code = round((float(np.median(ranges_m)) * 1000.0 - self.base) / 10.0)
        return max(k for k in list(self.taken) if k % 500 == code)


def collect_stamps(laser, source, count: int, liveness: float = 120.0) -> list[tuple[int, float, float]]:
    """(scan index, stamp, host time it was seen by) of ``count`` different scans of ``laser``
    (whichever the test's polling sees: a loaded machine may skip some)."""
    seen: dict[int, tuple[float, float]] = {}
    end = time.monotonic() + liveness                # bounds a hang only
    while len(seen) < count and time.monotonic() < end:
        s = laser.latest()
        now = time.monotonic()
        if s is not None:
            seen.setdefault(source.index(s.ranges), (s.stamp, now))
        time.sleep(0.005)
    return sorted((k, stamp, now) for k, (stamp, now) in seen.items())


def assert_stamps_are_measuring_times(seen, source, count: int) -> None:
    """Every stamp is the host time its scan was measured at, mapped from the device's clock by the
    smallest transfer delay seen so far: never before the measurement (beyond the device's rounding),
    never after the host had the scan, and, in the order of the scans, the stamp minus the measuring time
    only ever shrinks (the mapping's offset only improves).  A scan stamped when it arrived or when it
    was sent (30-60 ms after it was measured, varying) breaks the last one, whatever the load."""
    assert len(seen) >= count, seen
    offsets = []
    for k, stamp, by in seen:
        assert source.taken[k] - 0.001 <= stamp <= by, (k, stamp, source.taken[k], by)
        offsets.append(stamp - source.taken[k])
    assert all(b <= a + 0.0011 for a, b in zip(offsets, offsets[1:])), offsets
