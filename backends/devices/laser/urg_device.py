"""A Hokuyo URG as the host sees it over SCIP 2.0 (device side, no I/O).

:class:`UrgDevice` takes the host's bytes (:meth:`receive`), produces the
device's (:meth:`take_output`) and, while an MD/MS stream runs, one scan per
revolution (:meth:`advance`).  Distances come from ``source(t)``: the
ranges in millimetres of steps 0..``model.max_step`` at device time ``t``
(seconds since power-up), ``0`` or ``nan`` where nothing reflects.  A step
outside AMIN..AMAX, a distance outside DMIN..DMAX and no reflection are
sent as error code ``1`` (a value below DMIN, as the sensor does).
With ``on_cast`` (a source fed by a world, :mod:`.source`) a stream sends a
scan as soon as the source has ranges it has not sent (stamped when they
were measured), and on its own clock only when none came for two scan
periods (the newest again, with its old stamp).

What it does (spec C-42-03320B): the URG-04LX starts in SCIP 1.1 and
answers anything but ``SCIP2.0`` with the status ``E``; ``VV``/``PP``/``II``;
``BM`` (``02`` when already on), ``QT``, ``RS`` (resets the timer), ``GD``/``GS``
(``10`` with the laser off), ``MD``/``MS`` (``00`` acknowledgement with an
empty data part, then per scan the echo with the remaining count, ``99``,
time stamp and data; the laser goes off after a finite count), ``TM0/1/2``,
``SS``, ``CR``, ``HS``; parameter errors ``01``..``07``, ``0C`` (length),
``0E`` (unknown command), ``0G``/``0H`` (string).  Time stamps are the
device's milliseconds since power-up modulo 2**24.
"""
from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from . import scip
from .source import sample

NO_ECHO = 1           # an error code (below DMIN) sent where nothing is measured


@dataclass(frozen=True)
class UrgModel:
    name: str
    dmin: int                  # mm
    dmax: int                  # mm
    ares: int                  # steps per revolution
    amin: int                  # first measurable step
    amax: int                  # last measurable step
    afrt: int                  # step straight ahead
    max_step: int              # last step a command may name
    rpm: int                   # scans per minute
    scip1_at_boot: bool = False
    firmware: str = "3.4.03(17/Dec./2012)"
    serial: str = "H1312345"

    @property
    def scan_period(self) -> float:
        return 60.0 / self.rpm

    def step_angle(self, step) -> np.ndarray:
        """Angle (rad, counter-clockwise from the front) of a step."""
        return (np.asarray(step, dtype=float) - self.afrt) * (2.0 * math.pi / self.ares)


URG_04LX = UrgModel("URG-04LX-UG01", dmin=20, dmax=5600, ares=1024, amin=44, amax=725, afrt=384,
                    max_step=768, rpm=600, scip1_at_boot=True)
UTM_30LX = UrgModel("UTM-30LX", dmin=23, dmax=30000, ares=1440, amin=0, amax=1080, afrt=540,
                    max_step=1080, rpm=2400, firmware="1.20.00(27/Aug./2013)", serial="H1412345")
MODELS = {"URG-04LX": URG_04LX, "URG-04LX-UG01": URG_04LX, "UTM-30LX": UTM_30LX}

BITRATES = {19200, 38400, 57600, 115200, 250000, 500000, 750000}
_ECHO_ONLY = {"BM", "QT", "RS", "VV", "PP", "II"}


class UrgDevice:
    def __init__(self, model: UrgModel = URG_04LX, source: Callable[[float], np.ndarray] | None = None,
                 start: float = 0.0, on_cast: bool = False):
        self.model = model
        self.on_cast = on_cast
        self.source = source or (lambda t: np.zeros(model.max_step + 1))
        self.boot = start
        self._out = bytearray()
        self._rx = bytearray()
        self.scip2 = not model.scip1_at_boot
        self.laser_on = False
        self.bitrate = 115200
        self.time_adjust = False
        self.stream: dict | None = None
        self.commands = 0
        self.scans_sent = 0
        self.errors_sent = 0
        self._last_scan = start

    # -- time -------------------------------------------------------------------
    def stamp(self, now: float) -> int:
        return round((now - self.boot) * 1000.0) % (1 << 24)

    def _scan_index(self, now: float) -> int:
        return math.floor((now - self.boot) / self.model.scan_period)

    # -- I/O ----------------------------------------------------------------------
    def receive(self, data: bytes, now: float) -> None:
        self._rx += data
        while True:
            ends = [i for i in (self._rx.find(b"\n"), self._rx.find(b"\r")) if i >= 0]
            if not ends:
                if len(self._rx) > 512:           # garbage without a line end
                    self._rx.clear()
                return
            i = min(ends)
            line = bytes(self._rx[:i])
            del self._rx[:i + 1]
            if line:
                self.commands += 1
                self._command(line, now)

    def new_link(self) -> UrgDevice:
        """A host connected (the TCP port of an Ethernet URG): nothing half
        read or unsent is left over and no stream runs; the laser stays as it was."""
        self._rx.clear()
        self._out.clear()
        self.stream = None
        return self

    def take_output(self) -> bytes:
        out, self._out = bytes(self._out), bytearray()
        return out

    def next_due(self) -> float | None:
        """When the stream's next scan is due (None: no stream runs; on a cast: the latest it goes out)."""
        s = self.stream
        if s is None:
            return None
        if self.on_cast:
            return s["sent_at"] + 2 * (1 + s["interval"]) * self.model.scan_period
        return s["next"] * self.model.scan_period + self.boot

    def advance(self, now: float) -> None:
        """Send the stream's scans that are due by ``now``."""
        if self.on_cast:
            return self._advance_on_cast(now)
        s = self.stream
        while s is not None and s["next"] * self.model.scan_period + self.boot <= now:
            k = s["next"]
            s["next"] += 1 + s["interval"]
            t = k * self.model.scan_period
            raw, taken = sample(self.source, t)
            self._stream_scan(s, raw, taken if math.isfinite(taken) else t)
            s = self.stream

    def _advance_on_cast(self, now: float) -> None:
        """The stream's scan of ranges measured since the last one (the ``interval``
        after it skipped), or of the newest ones when none came for two scan periods."""
        s = self.stream
        if s is None:
            return
        raw, taken = sample(self.source, now - self.boot)
        if taken > s["taken"]:                     # measured since the last scan (or the stream's start)
            s["taken"] = taken
            if s["skip"] > 0:
                s["skip"] -= 1
                return
        elif now < self.next_due():
            return
        s["skip"] = s["interval"]
        s["sent_at"] = now
        self._stream_scan(s, raw, taken if math.isfinite(taken) else now - self.boot)   # -inf: nothing cast yet

    def _stream_scan(self, s: dict, raw: np.ndarray, taken: float) -> None:
        if s["count"]:
            s["left"] -= 1
        echo = (f"{s['symbol']}{s['start']:04d}{s['end']:04d}{s['cluster']:02d}{s['interval']:01d}"
                f"{max(s['left'], 0):02d}").encode() + s["tag"]
        self._out += echo + b"\n" + scip.status_line("99") + self._payload(s, raw, taken)
        self.scans_sent += 1
        if s["count"] and s["left"] <= 0:
            self.stream = None
            self.laser_on = False

    # -- commands -----------------------------------------------------------------
    def _reply(self, echo: bytes, status: str, body: bytes = b"") -> None:
        if status not in ("00", "99"):
            self.errors_sent += 1
        self._out += echo + b"\n" + scip.status_line(status) + body + b"\n"

    def _command(self, line: bytes, now: float) -> None:
        if not self.scip2:
            if line == b"SCIP2.0":
                self.scip2 = True
                self._out += b"SCIP2.0\n0\n\n"
            else:                                 # SCIP 1.1 does not know it
                self._out += line + b"\nE\n\n"
            return
        if line == b"SCIP2.0":
            self._out += b"SCIP2.0\n0\n\n"
            return
        body, sep, tag = line.partition(b";")
        if sep:
            if len(tag) > scip.MAX_STRING:
                return self._reply(line, "0G")
            if not set(tag) <= scip.STRING_CHARS:
                return self._reply(line, "0H")
        symbol = body[:2].decode("ascii", "replace")
        params = body[2:].decode("ascii", "replace")
        handler = getattr(self, f"_cmd_{symbol}", None) if symbol.isalpha() and symbol.isupper() else None
        if handler is None:
            return self._reply(line, "0E")
        if symbol in _ECHO_ONLY and params:
            return self._reply(line, "0C")
        handler(line, params, b";" + tag if sep else b"", now)

    def _cmd_VV(self, echo, params, tag, now):
        m = self.model
        body = (scip.info_line("VEND", "Hokuyo Automatic Co.,Ltd.")
                + scip.info_line("PROD", f"SOKUIKI Sensor {m.name}") + scip.info_line("FIRM", m.firmware)
                + scip.info_line("PROT", "SCIP 2.0") + scip.info_line("SERI", m.serial))
        self._reply(echo, "00", body)

    def _cmd_PP(self, echo, params, tag, now):
        m = self.model
        body = b"".join(scip.info_line(k, str(v)) for k, v in (
            ("MODL", f"{m.name}(Hokuyo Automatic Co.,Ltd.)"), ("DMIN", m.dmin), ("DMAX", m.dmax),
            ("ARES", m.ares), ("AMIN", m.amin), ("AMAX", m.amax), ("AFRT", m.afrt), ("SCAN", m.rpm)))
        self._reply(echo, "00", body)

    def _cmd_II(self, echo, params, tag, now):
        m = self.model
        mode = "Measuring by Sensitive Mode" if self.stream or self.laser_on else "IDLE"
        body = b"".join(scip.info_line(k, v) for k, v in (
            ("MODL", f"{m.name}(Hokuyo Automatic Co.,Ltd.)"), ("LASR", "ON" if self.laser_on else "OFF"),
            ("SCSP", f"Initial({m.rpm}[rpm])"), ("MESM", mode), ("SBPS", f"{self.bitrate}[bps]"),
            ("TIME", f"{self.stamp(now):06X}"), ("STAT", "Sensor works well.")))
        self._reply(echo, "00", body)

    def _cmd_BM(self, echo, params, tag, now):
        if self.laser_on:
            return self._reply(echo, "02")
        self.laser_on = True
        self._reply(echo, "00")

    def _cmd_QT(self, echo, params, tag, now):
        self.stream = None
        self.laser_on = False
        self._reply(echo, "00")

    def _cmd_RS(self, echo, params, tag, now):
        self.stream = None
        self.laser_on = False
        self.bitrate = 115200
        self.time_adjust = False
        self.boot = now                       # the internal timer restarts
        self._reply(echo, "00")

    def _scan_params(self, params: str, continuous: bool) -> tuple[str, tuple]:
        need = 15 - 2 if continuous else 12 - 2
        if len(params) != need:
            return "0C", ()
        fields = [(params[0:4], "01"), (params[4:8], "02"), (params[8:10], "03")]
        if continuous:
            fields += [(params[10:11], "06"), (params[11:13], "07")]
        values = []
        for text, err in fields:
            if not text.isdigit():
                return err, ()
            values.append(int(text))
        start, end = values[0], values[1]
        if end > self.model.max_step:
            return "04", ()
        if end < start:
            return "05", ()
        return "00", tuple(values)

    def _gd(self, echo, params, now, size):
        status, values = self._scan_params(params, continuous=False)
        if status != "00":
            return self._reply(echo, status)
        if not self.laser_on:
            return self._reply(echo, "10")
        start, end, cluster = values
        t = self.boot + max(self._scan_index(now), 0) * self.model.scan_period
        s = {"start": start, "end": end, "cluster": cluster, "size": size}
        self._out += echo + b"\n" + scip.status_line("00") + self._scan_payload(s, t)
        self.scans_sent += 1

    def _cmd_GD(self, echo, params, tag, now):
        self._gd(echo, params, now, 3)

    def _cmd_GS(self, echo, params, tag, now):
        self._gd(echo, params, now, 2)

    def _md(self, echo, params, tag, now, symbol, size):
        status, values = self._scan_params(params, continuous=True)
        if status != "00":
            return self._reply(echo, status)
        start, end, cluster, interval, count = values
        self.laser_on = True
        self._reply(echo, "00")
        self.stream = {"symbol": symbol, "start": start, "end": end, "cluster": cluster, "interval": interval,
                       "count": count, "left": count, "size": size, "tag": tag,
                       "next": self._scan_index(now) + 1,
                       # on a cast: the first scan is of ranges measured after the command
                       "taken": now - self.boot, "skip": 0, "sent_at": now}

    def _cmd_MD(self, echo, params, tag, now):
        self._md(echo, params, tag, now, "MD", 3)

    def _cmd_MS(self, echo, params, tag, now):
        self._md(echo, params, tag, now, "MS", 2)

    def _cmd_TM(self, echo, params, tag, now):
        if params not in ("0", "1", "2"):
            return self._reply(echo, "01")
        if params == "0":
            if self.time_adjust:
                return self._reply(echo, "02")
            self.time_adjust = True
            return self._reply(echo, "00")
        if params == "2":
            if not self.time_adjust:
                return self._reply(echo, "03")
            self.time_adjust = False
            return self._reply(echo, "00")
        if not self.time_adjust:
            return self._reply(echo, "04")
        self._reply(echo, "00", scip.sum_line(scip.encode(self.stamp(now), 4)))

    def _cmd_SS(self, echo, params, tag, now):
        if len(params) != 6 or not params.isdigit() or int(params) not in BITRATES:
            return self._reply(echo, "01")
        if int(params) == self.bitrate:
            return self._reply(echo, "03")
        self.bitrate = int(params)
        self._reply(echo, "00")

    def _cmd_CR(self, echo, params, tag, now):
        if len(params) != 2 or not params.isdigit():
            return self._reply(echo, "01")
        if not (0 <= int(params) <= 10 or int(params) == 99):
            return self._reply(echo, "02")
        self._reply(echo, "00")

    def _cmd_HS(self, echo, params, tag, now):
        if params not in ("0", "1"):
            return self._reply(echo, "01")
        self._reply(echo, "00")

    # -- data -----------------------------------------------------------------------
    def measure(self, t: float, start: int, end: int, cluster: int, size: int) -> list[int]:
        """The values sent for steps ``start..end`` at device time ``t``."""
        return self._measure(t, start, end, cluster, size)[0]

    def _measure(self, t: float, start: int, end: int, cluster: int, size: int) -> tuple[list[int], float]:
        """(:meth:`measure`, the clock time the source measured them at: ``t`` unless it says otherwise)."""
        raw, taken = sample(self.source, t - self.boot)
        taken = taken if math.isfinite(taken) else t - self.boot
        return self._values(raw, start, end, cluster, size), self.boot + taken

    def _values(self, raw: np.ndarray, start: int, end: int, cluster: int, size: int) -> list[int]:
        """The values sent for steps ``start..end`` of the source's ranges ``raw`` (mm)."""
        m = self.model
        steps = np.arange(start, end + 1)
        mm = np.full(len(steps), float(NO_ECHO))
        inside = (steps >= m.amin) & (steps <= m.amax) & (steps < len(raw))
        vals = raw[steps[inside]]
        limit = min(m.dmax, 4095) if size == 2 else m.dmax
        good = np.isfinite(vals) & (vals >= m.dmin) & (vals <= limit)
        vals = np.where(good, np.round(vals), NO_ECHO)
        mm[inside] = vals
        c = max(cluster, 1)
        groups = np.full(-(-len(mm) // c) * c, np.inf)         # padded to whole clusters
        groups[:len(mm)] = mm
        groups = groups.reshape(-1, c)
        # a cluster sends its nearest echo; with none, its first step's error code
        echoes = np.where(groups >= m.dmin, groups, np.inf).min(axis=1)
        return np.where(np.isfinite(echoes), echoes, groups[:, 0]).astype(int).tolist()

    def _scan_payload(self, s: dict, t: float) -> bytes:
        raw, taken = sample(self.source, t - self.boot)
        return self._payload(s, raw, taken if math.isfinite(taken) else t - self.boot)

    def _payload(self, s: dict, raw: np.ndarray, taken: float) -> bytes:
        """A scan's time stamp and data of ranges ``raw`` measured at device time ``taken``."""
        values = self._values(raw, s["start"], s["end"], s["cluster"], s["size"])
        self._last_scan = self.boot + taken
        return (scip.sum_line(scip.encode(self.stamp(self.boot + taken), 4))
                + scip.data_block(scip.encode_values(values, s["size"])) + b"\n")
