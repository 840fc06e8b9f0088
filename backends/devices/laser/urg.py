"""Hokuyo URG driver: SCIP 2.0 over a USB CDC-ACM serial line.

    laser = UrgLaser("/dev/ttyACM1", mount=LaserMount(x=0.12)).start(wait=2.0)
    scan = laser.latest()          # rll_bt.backend.LaserScan, host time stamp

On connect: ``QT`` (stops a stream another program left running and tells
SCIP 1.1 from 2.0: SCIP 1.1 answers ``E``, and then gets ``SCIP2.0``),
``PP`` (the scan geometry: DMIN, DMAX, ARES, AMIN, AMAX, AFRT, SCAN), ``VV``,
then either ``MD`` (``mode="stream"``: the sensor sends every scan) or ``BM``
and one ``GD`` per scan period (``mode="poll"``).  ``encoding=2`` uses
MS/GS (12-bit values, up to 4095 mm).  Every line's checksum is checked; a
block that fails is counted and dropped.  Distances below DMIN are the
sensor's error codes and become ``inf``, like distances beyond DMAX.  The
device's millisecond stamp (24 bits, wrapping every 4.6 h) is mapped to the
host clock by :class:`~.stamps.DeviceClock`.  Reconnects as
:class:`~.base.LaserDriver` says (no scan for ``timeout`` s: closed and
reopened).  The codec is :mod:`.scip` (why it is written here is said there).
"""
from __future__ import annotations

import logging
import math
import select

import numpy as np

from rll_bt.backend import BackendError, LaserScan

from . import scip
from .base import LaserDriver, LinkLost
from .stamps import DeviceClock

log = logging.getLogger(__name__)

REQUIRED = ("DMIN", "DMAX", "ARES", "AMIN", "AMAX", "AFRT", "SCAN")


class UrgLaser(LaserDriver):
    kind = "urg"

    def __init__(self, device: str, *, mode: str = "stream", encoding: int = 3, cluster: int = 1,
                 reply_timeout: float = 1.0, **options):
        if mode not in ("stream", "poll"):
            raise ValueError(f"mode must be 'stream' or 'poll', not {mode!r}")
        if encoding not in (2, 3):
            raise ValueError(f"encoding must be 2 (MS/GS) or 3 (MD/GD), not {encoding}")
        if not 1 <= cluster <= 99:
            raise ValueError(f"cluster must be 1..99, not {cluster}")
        super().__init__(**options)
        self.device = device
        self.mode = mode
        self.encoding = encoding
        self.cluster = cluster
        self.reply_timeout = reply_timeout
        self._port = None
        self._reader = scip.BlockReader()
        self._clock = DeviceClock(1 << 24, 1e-3)
        self.params: dict[str, int] = {}
        self.scip11_switches = 0
        self._pending_gd = False
        self._next_poll = 0.0

    def describe(self) -> str:
        return f"URG on {self.device}"

    # -- link ---------------------------------------------------------------------
    def _write(self, data: bytes) -> None:
        from backends.robotino.serial_port import write_all
        if self._port is None:
            raise LinkLost("port closed")
        write_all(self._port, data)

    def _blocks(self, timeout: float) -> list[scip.Block]:
        port = self._port
        if port is None:
            raise LinkLost("port closed")
        ready, _, _ = select.select([port.fileno()], [], [], timeout)
        if not ready:
            return []
        data = port.read(4096)
        if not data:            # readable but empty: the device went away
            raise LinkLost("device gone")
        return self._reader.feed(data)

    def _await(self, symbol: bytes, what: str) -> scip.Block:
        """The reply whose echo starts with ``symbol`` (others are dropped)."""
        end = self.clock.now() + self.reply_timeout
        while self.clock.now() < end:
            for block in self._blocks(0.02):
                if block.echo.startswith(symbol):
                    return block
        raise LinkLost(f"no reply to {what} within {self.reply_timeout:g} s")

    def _request(self, cmd: bytes, ok=("00",)) -> scip.Block:
        self._write(cmd)
        block = self._await(cmd.rstrip(b"\n"), cmd.decode().strip())
        try:
            status = block.status
        except scip.ScipError as exc:
            raise LinkLost(str(exc)) from None
        if status not in ok:
            raise LinkLost(f"{cmd.decode().strip()} answered {status} "
                           f"({scip.STATUS_TEXT.get(status, 'unknown status')})")
        return block

    def _connect(self) -> None:
        from backends.robotino.serial_port import open_serial
        try:
            self._port = open_serial(self.device)
        except BackendError as exc:
            raise LinkLost(str(exc)) from None
        self._reader.reset()
        self._port.reset_input_buffer()
        self._write(b"QT\n")
        qt = self._await(b"QT", "QT")
        if qt.lines and qt.lines[0] == b"E":            # SCIP 1.1: switch
            self._request(b"SCIP2.0\n", ok=("0",))
            self.scip11_switches += 1
            self._request(b"QT\n")
        try:
            pp = self._request(b"PP\n").info()
            self.info = self._request(b"VV\n").info()
            missing = [k for k in REQUIRED if k not in pp]
            if missing:
                raise LinkLost(f"PP without {', '.join(missing)}")
            self.params = {k: int(pp[k]) for k in REQUIRED}
        except (scip.ScipError, ValueError) as exc:
            raise LinkLost(f"bad parameters: {exc}") from None
        self.info["MODL"] = pp.get("MODL", "")
        self._clock.reset()
        p = self.params
        if self.mode == "stream":
            symbol = "MD" if self.encoding == 3 else "MS"
            self._request(scip.scan_command(symbol, p["AMIN"], p["AMAX"], self.cluster, 0, 0))
        else:
            self._request(b"BM\n", ok=("00", "02"))
            self._pending_gd = False
            self._next_poll = self.clock.now()

    def _disconnect(self) -> None:
        port, self._port = self._port, None
        if port is not None:
            try:
                port.write(b"QT\n")        # leave the laser off
            except OSError as exc:
                log.debug("%s: QT on close failed: %s", self.describe(), exc)
            port.close()

    # -- scans -----------------------------------------------------------------------
    def _read(self, timeout: float) -> list[LaserScan]:
        if self.mode == "poll":
            now = self.clock.now()
            if not self._pending_gd and now >= self._next_poll:
                p = self.params
                symbol = "GD" if self.encoding == 3 else "GS"
                self._write(scip.scan_command(symbol, p["AMIN"], p["AMAX"], self.cluster))
                self._pending_gd = True
                self._next_poll = max(now, self._next_poll) + 60.0 / p["SCAN"]
            timeout = min(timeout, max(0.0, self._next_poll - now))
        out = []
        for block in self._blocks(timeout):
            received = self.clock.now()
            try:
                scan = self._on_block(block, received)
            except scip.ScipError as exc:
                self._error(str(exc))
                continue
            if scan is not None:
                out.append(scan)
        return out

    def _on_block(self, block: scip.Block, received: float) -> LaserScan | None:
        symbol = block.command
        status = block.status
        if symbol in ("MD", "MS") and status == "99":
            return self._decode_scan(block, received)
        if symbol in ("GD", "GS"):
            self._pending_gd = False
            if status == "00":
                return self._decode_scan(block, received)
            if status == "10":                       # the laser went off: on again
                self._write(b"BM\n")
        if status not in ("00", "99"):
            self._error(f"{block.echo.decode(errors='replace')}: status {status} "
                        f"({scip.STATUS_TEXT.get(status, 'hardware trouble' if status >= '50' else 'unknown')})",
                        device=True)
        return None

    def _decode_scan(self, block: scip.Block, received: float) -> LaserScan:
        size = 2 if block.command[1] == "S" else 3
        raw_stamp, values = block.scan(size)
        echo = block.echo.decode("ascii", "replace")
        try:
            start, end, cluster = int(echo[2:6]), int(echo[6:10]), max(int(echo[10:12]), 1)
        except ValueError:
            raise scip.ScipError(f"bad echo {echo!r}") from None
        expected = -(-(end - start + 1) // cluster)
        if len(values) != expected:
            raise scip.ScipError(f"{len(values)} values for steps {start}..{end} / {cluster}, expected {expected}")
        p = self.params
        mm = np.asarray(values, dtype=float)
        ranges = np.where((mm >= p["DMIN"]) & (mm <= p["DMAX"]), mm / 1000.0, np.inf)
        step = 2.0 * math.pi / p["ARES"]
        angle_min = (start + (cluster - 1) / 2.0 - p["AFRT"]) * step
        stamp = self._clock.to_host(raw_stamp, received)
        return self.mount.scan(stamp, angle_min, step * cluster, ranges, p["DMIN"] / 1000.0, p["DMAX"] / 1000.0)
