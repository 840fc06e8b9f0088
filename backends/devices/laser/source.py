"""What an emulated scanner's ``source(t)`` gives: the ranges (mm) at device
time ``t`` (seconds since power-up), or ``(ranges, taken)`` when they were
measured at another device time ``taken``.

A scanner fed by a world that casts its rays at moments of its own (after
a world step, :mod:`backends.sim.hardware`) would send the newest ranges when
its own clock says a scan is due, up to a scan period after they were cast;
stamped with the due time, a scan of a robot turning at 1.6 rad/s then read
up to 0.16 rad off its odometry.  A real scanner stamps the moment it
measured: so does the emulator, with ``taken``.  And a real scanner sends
a scan as soon as it has measured it, a fixed few milliseconds later: the
host maps the device's stamps onto its own clock by the smallest delay it
sees (:class:`~.stamps.DeviceClock`), which cannot tell a constant delay
from none.  A scanner that sent a world's cast only at its own next due
time did so a fixed phase after the cast (0.03-0.046 s on a loaded
machine), and every stamp was that much early on the host.  So a world
that casts tells the scanner at once (:class:`CastSignal`), and the
scanner sends the scan right after the cast (``on_cast`` of the URG and
TiM devices).
"""
from __future__ import annotations

import socket

import numpy as np


def sample(source, t: float) -> tuple[np.ndarray, float]:
    """(ranges in mm, the device time they were measured at) of ``source`` at device time ``t``."""
    got = source(t)
    if isinstance(got, tuple):
        ranges, taken = got
        return np.asarray(ranges, dtype=float), float(taken)
    return np.asarray(got, dtype=float), t


class CastSignal:
    """The world's "ranges cast" to the thread that serves the scanner: a
    socket pair whose reading end that thread waits on beside its port
    (``select``).  :meth:`notify` never blocks (a full buffer already says
    "cast"); it survives pickling into a child process (``spawn``), so the
    world's process can wake a scanner in the devices' process."""

    def __init__(self):
        self._r, self._w = socket.socketpair()
        self._r.setblocking(False)
        self._w.setblocking(False)

    def fileno(self) -> int:
        return self._r.fileno()

    def notify(self) -> None:
        try:
            self._w.send(b"\0")
        except (BlockingIOError, OSError):        # full (a wake-up is waiting) or closed
            pass

    def drain(self) -> None:
        try:
            while self._r.recv(4096):
                pass
        except (BlockingIOError, OSError):
            pass

    def close(self) -> None:
        self._r.close()
        self._w.close()
