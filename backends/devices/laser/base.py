"""What every laser driver shares: an I/O thread that connects, reads scans
and reconnects, the newest scan kept for whoever asks, health and rates.

A driver subclass implements :meth:`LaserDriver._connect` (open and set the
device up; raise :class:`LinkLost` or :class:`OSError` when it cannot),
:meth:`LaserDriver._read` (the scans that arrived within a short wait,
raising :class:`LinkLost` on a broken link) and :meth:`LaserDriver._disconnect`.
The base class runs the loop: no scan for ``timeout`` seconds counts as a
lost link (the device is closed and reopened every ``reopen_interval``).

Scans come out as :class:`rll_bt.backend.LaserScan` in the robot's terms:
angles counter-clockwise from the laser's front, ``mount`` the laser's pose
in the robot frame; a laser mounted upside down has its beam order
reversed so that the angles stay counter-clockwise in the robot frame.
"""
from __future__ import annotations

import logging
import math
import threading
from collections import deque
from dataclasses import dataclass, replace

import numpy as np

from rll_bt.backend import LaserScan, Pose2D
from rll_bt.clock import Clock, WallClock

log = logging.getLogger(__name__)


class LinkLost(Exception):
    """The device stopped answering or its port went away."""


@dataclass(frozen=True)
class LaserMount:
    """Where the laser sits on the robot: x, y (m), yaw (rad) in the robot
    frame, height z (m, for the record) and whether it is upside down."""
    x: float = 0.0
    y: float = 0.0
    z: float = 0.2
    yaw: float = 0.0
    upside_down: bool = False

    @property
    def pose(self) -> Pose2D:
        return Pose2D(self.x, self.y, self.yaw)

    def scan(self, stamp: float, angle_min: float, increment: float, ranges: np.ndarray,
             range_min: float, range_max: float) -> LaserScan:
        """A scan of the device (its own counter-clockwise angles) in the robot's terms."""
        r = np.asarray(ranges, dtype=float)
        if self.upside_down:           # seen from above, the device turns clockwise
            r = r[::-1]
            angle_min = -(angle_min + increment * (len(r) - 1))
        return LaserScan(stamp, angle_min, increment, range_min, range_max, r, mount=self.pose)


@dataclass
class LaserStats:
    connected: bool = False
    scans: int = 0
    connects: int = 0
    link_losses: int = 0
    errors: int = 0                  # replies that broke the protocol (checksum, framing)
    device_errors: int = 0           # error statuses the device sent
    last_error: str = ""
    last_scan_at: float = math.nan   # host time a scan last arrived
    rate: float = 0.0                # scans per second over the last few seconds


class LaserDriver:
    """Base of the drivers (see the module doc)."""

    kind = "laser"

    def __init__(self, *, mount: LaserMount | None = None, clock: Clock | None = None,
                 timeout: float = 1.0, reopen_interval: float = 0.25):
        self.mount = mount or LaserMount()
        self.clock = clock or WallClock()
        self.timeout = timeout
        self.reopen_interval = reopen_interval
        self._lock = threading.Lock()
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None
        self._scan: LaserScan | None = None
        self._stats = LaserStats()
        self._arrivals: deque = deque(maxlen=50)
        self.info: dict[str, str] = {}

    # -- life cycle -------------------------------------------------------------
    def start(self, wait: float | None = None) -> LaserDriver:
        """Start the I/O thread; with ``wait``, block until the first scan
        (:class:`LinkLost` if none came within ``wait`` seconds)."""
        self._stop.clear()
        self._thread = threading.Thread(target=self._run, name=f"{self.kind}-io", daemon=True)
        self._thread.start()
        if wait is not None:
            end = self.clock.now() + wait
            while self.latest() is None:
                if self.clock.now() >= end:
                    self.close()
                    why = self.stats().last_error or "no reply"
                    raise LinkLost(f"{self.describe()}: no scan within {wait:g} s ({why})")
                self._stop.wait(0.01)
        return self

    def close(self) -> None:
        self._stop.set()
        if self._thread is not None:
            self._thread.join(timeout=2.0)
            self._thread = None
        self._safe_disconnect()

    def describe(self) -> str:
        return self.kind

    # -- readings -----------------------------------------------------------------
    def latest(self) -> LaserScan | None:
        with self._lock:
            return self._scan

    def stats(self) -> LaserStats:
        with self._lock:
            s = replace(self._stats)
        if len(self._arrivals) >= 2 and self.clock.now() - self._arrivals[-1] < 2.0:
            span = self._arrivals[-1] - self._arrivals[0]
            s.rate = (len(self._arrivals) - 1) / span if span > 0 else 0.0
        return s

    def healthy(self, stale: float) -> bool:
        """Connected and a scan arrived within ``stale`` seconds."""
        with self._lock:
            last = self._stats.last_scan_at
            return self._stats.connected and not math.isnan(last) and self.clock.now() - last <= stale

    # -- for subclasses -----------------------------------------------------------
    def _connect(self) -> None:
        raise NotImplementedError

    def _read(self, timeout: float) -> list[LaserScan]:
        raise NotImplementedError

    def _disconnect(self) -> None:
        raise NotImplementedError

    def _error(self, text: str, device: bool = False) -> None:
        with self._lock:
            if device:
                self._stats.device_errors += 1
            else:
                self._stats.errors += 1
            self._stats.last_error = text
        log.debug("%s: %s", self.describe(), text)

    # -- the loop -------------------------------------------------------------------
    def _safe_disconnect(self) -> None:
        try:
            self._disconnect()
        except (OSError, LinkLost) as exc:            # closing a dead link must not raise
            log.debug("%s: closing: %s", self.describe(), exc)

    def _run(self) -> None:
        while not self._stop.is_set():
            try:
                self._connect()
            except Exception as exc:
                if not isinstance(exc, (LinkLost, OSError)):
                    log.exception("%s: connect failed", self.describe())
                with self._lock:
                    self._stats.last_error = str(exc)
                self._safe_disconnect()
                self._stop.wait(self.reopen_interval)
                continue
            with self._lock:
                self._stats.connected = True
                self._stats.connects += 1
            log.info("%s connected", self.describe())
            last = self.clock.now()
            try:
                while not self._stop.is_set():
                    scans = self._read(0.05)
                    now = self.clock.now()
                    if scans:
                        last = now
                        with self._lock:
                            self._scan = scans[-1]
                            self._stats.scans += len(scans)
                            self._stats.last_scan_at = now
                        self._arrivals.extend([now] * len(scans))
                    elif now - last > self.timeout:
                        raise LinkLost(f"no scan for {now - last:.2f} s")
            except Exception as exc:          # LinkLost, OSError, or a bug: never kill the thread
                if not isinstance(exc, (LinkLost, OSError)):
                    log.exception("%s: driver error", self.describe())
                log.warning("%s: link lost (%s); reopening", self.describe(), exc)
                with self._lock:
                    self._stats.link_losses += 1
                    self._stats.last_error = str(exc)
            finally:
                with self._lock:
                    self._stats.connected = False
                self._safe_disconnect()
            self._stop.wait(self.reopen_interval)
