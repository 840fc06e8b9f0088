"""What an emulated scanner's ``source(t)`` gives: the ranges (mm) at device
time ``t`` (seconds since power-up), or ``(ranges, taken)`` when they were
measured at another device time ``taken``.

A scanner fed by a world that casts its rays at moments of its own (after
a world step, :mod:`backends.sim.hardware`) sends the newest ranges when its
scan is due, up to a scan period after they were cast; stamped with the due
time, a scan of a robot turning at 1.6 rad/s then read up to 0.16 rad off
its odometry.  A real scanner stamps the moment it measured: so does the
emulator, with ``taken``.
"""
from __future__ import annotations

import numpy as np


def sample(source, t: float) -> tuple[np.ndarray, float]:
    """(ranges in mm, the device time they were measured at) of ``source`` at device time ``t``."""
    got = source(t)
    if isinstance(got, tuple):
        ranges, taken = got
        return np.asarray(ranges, dtype=float), float(taken)
    return np.asarray(got, dtype=float), t
