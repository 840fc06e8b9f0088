"""A SICK TiM5xx as its CoLa clients see it (device side, no I/O).

:class:`TimDevice` holds the scanner (model, clocks, counters, the scan
``source``); each TCP connection is a :class:`TimSession` with its own input
buffer, dialect (the one of the last request: CoLa-A or CoLa-B) and stream
flag.  ``session.receive(data, now)`` parses requests, ``session.advance(now)``
adds a ``sSN LMDscandata`` for every scan measured since, while the session
streams; ``session.take_output()`` is what goes back.

Scans are measured at the scan frequency from power-up; distances come
from ``source(t)``: millimetres of the model's ``count`` beams (from
``start_angle`` in ``step`` increments, the scanner's angles, 90 degrees
ahead) at device time ``t`` seconds; ``0``/``nan`` or outside the range
becomes 0 (no echo).  With ``on_cast`` (a source fed by a world,
:mod:`.source`) a streaming session sends a scan as soon as the source has
ranges it has not sent (stamped when they were measured), and on its own
clock only when none came for two scan periods (the newest again, with its
old stamp).  Requests answered (others: ``sFA``):

* ``sRN LMDscandata``, ``sEN LMDscandata 0|1``;
* ``sMN SetAccessMode <level> <password>`` (``03 F4724744`` authorised
  client, ``02 B21ACE26`` maintenance) -> ``sAN SetAccessMode 1|0``;
* ``sRI0``/``sRN DeviceIdent``, ``SerialNumber``, ``FirmwareVersion``,
  ``SCdevicestate``, ``LMPscancfg``, ``LocationName``, ``ODoprh``, ``ODpwrc``;
* ``sMN LMCstartmeas``/``LMCstopmeas``/``Run``/``mSCreboot`` (need access);
  ``sWN LMDscandatacfg|LMPoutputRange|... `` -> ``sWA`` (need access).
"""
from __future__ import annotations

import math
import struct
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from . import cola
from .source import sample

PASSWORDS = {2: "B21ACE26", 3: "F4724744"}
WRITABLE = {"LMDscandatacfg", "LMPoutputRange", "FREchoFilter", "LFPparticle", "LFPmeanfilter",
            "LocationName", "MCSenseLevel", "SetActiveApplications"}


@dataclass(frozen=True)
class TimModel:
    name: str = "TiM571"
    firmware: str = "V3.32 Feb 2019"       # 14 characters, as sick_tim expects ("E")
    serial: int = 0x12D0A4B
    start_angle: int = -450000              # 1/10000 degree
    step: int = 3333                        # 1/10000 degree (0.3333)
    count: int = 811
    frequency: int = 1500                   # 1/100 Hz
    range_mm: tuple[int, int] = (50, 25000)

    @property
    def scan_period(self) -> float:
        return 100.0 / self.frequency

    @property
    def measurement_frequency(self) -> int:
        """Beams per second / 100 (a full turn's worth of steps)."""
        per_turn = round(360.0 * 10000 / self.step)
        return round(self.frequency / 100.0 * per_turn / 100.0)

    def angles(self) -> np.ndarray:
        """Beam angles in the robot's convention (rad, 0 ahead)."""
        deg = (self.start_angle + self.step * np.arange(self.count)) / 10000.0 - 90.0
        return np.radians(deg)


TIM571 = TimModel()
TIM551 = TimModel("TiM551", step=10000, count=271, range_mm=(50, 10000), serial=0x12D0A4C)
MODELS = {"TiM571": TIM571, "TiM551": TIM551}


class TimDevice:
    def __init__(self, model: TimModel = TIM571, source: Callable[[float], np.ndarray] | None = None,
                 start: float = 0.0, on_cast: bool = False):
        self.model = model
        self.on_cast = on_cast
        self.source = source or (lambda t: np.zeros(model.count))
        self.boot = start
        self.telegram_counter = 0
        self.scans_sent = 0
        self.errors_sent = 0

    def scan_index(self, now: float) -> int:
        return math.floor((now - self.boot) / self.model.scan_period)

    def micros(self, t: float) -> int:
        return round((t - self.boot) * 1e6) & 0xFFFFFFFF

    def scan(self, index: int, sent: float) -> cola.ScanData:
        """Scan ``index`` (measured on the device's clock), sent at ``sent``."""
        t = index * self.model.scan_period
        return self.scan_of(*sample(self.source, t), index, sent, t)

    def measured(self, now: float) -> tuple[np.ndarray, float]:
        """The source's newest ranges (mm) and the device time they were measured at (``-inf``: none yet)."""
        return sample(self.source, now - self.boot)

    def scan_of(self, mm: np.ndarray, taken: float, index: int, sent: float, when: float) -> cola.ScanData:
        """The scan of ranges ``mm`` measured at device time ``taken`` (``when`` if that is not finite)."""
        m = self.model
        mm, t = mm[:m.count], self.boot + (taken if math.isfinite(taken) else when)
        lo, hi = m.range_mm
        ok = np.isfinite(mm) & (mm >= lo) & (mm <= hi)
        values = np.where(ok, np.round(mm), 0).astype(int).tolist()
        values += [0] * (m.count - len(values))
        self.telegram_counter = (self.telegram_counter + 1) & 0xFFFF
        self.scans_sent += 1
        return cola.ScanData(serial=m.serial, telegram_counter=self.telegram_counter,
                             scan_counter=index & 0xFFFF, time_since_startup=self.micros(t),
                             time_of_transmission=self.micros(sent), scan_frequency=m.frequency,
                             measurement_frequency=m.measurement_frequency,
                             channels16=[cola.Channel("DIST1", 1.0, 0.0, m.start_angle, m.step, values)])

    def session(self) -> TimSession:
        return TimSession(self)


class TimSession:
    def __init__(self, device: TimDevice):
        self.device = device
        self.reader = cola.TelegramReader()
        self.binary = False
        self.streaming = False
        self.access = 0
        self.requests = 0
        self._next_scan = 0
        self._taken = self._sent_at = 0.0      # on a cast: the device time of the last ranges sent, when sent
        self._out = bytearray()

    def take_output(self) -> bytes:
        out, self._out = bytes(self._out), bytearray()
        return out

    def _send(self, payload: bytes) -> None:
        self._out += cola.frame_b(payload) if self.binary else cola.frame_a(payload)

    def _error(self, code: int) -> None:
        self.device.errors_sent += 1
        self._send(cola.error_answer(code, self.binary))

    def receive(self, data: bytes, now: float) -> None:
        for t in self.reader.feed(data):
            self.requests += 1
            self.binary = t.binary
            self._request(t.payload, now)

    def advance(self, now: float) -> None:
        if not self.streaming:
            return
        dev = self.device
        if dev.on_cast:
            return self._advance_on_cast(now)
        last = dev.scan_index(now)
        if self._next_scan > last:
            return
        self._next_scan = max(self._next_scan, last - 4)      # the emulator fell behind: no long backlog
        while self._next_scan <= last:
            self._send_scan("sSN", self._next_scan, now)
            self._next_scan += 1

    def next_due(self) -> float | None:
        """On a cast: the latest the next scan goes out (None: not streaming, or on the device's clock)."""
        if not (self.streaming and self.device.on_cast):
            return None
        return self._sent_at + 2 * self.device.model.scan_period

    def _advance_on_cast(self, now: float) -> None:
        """A scan of ranges measured since the last one, or of the newest ones when none came for two periods."""
        dev = self.device
        mm, taken = dev.measured(now)
        if not taken > self._taken and now < self.next_due():
            return
        self._taken = max(self._taken, taken)
        self._sent_at = now
        self._send_scan("sSN", self._next_scan, now, (mm, taken))
        self._next_scan += 1

    def _send_scan(self, kind: str, index: int, now: float, measured=None) -> None:
        dev = self.device
        s = (dev.scan(index, now) if measured is None
             else dev.scan_of(*measured, index, now, now - dev.boot))
        self._send(cola.encode_scan_b(kind, s) if self.binary else cola.encode_scan_a(kind, s))

    # -- requests -------------------------------------------------------------------
    def _args(self, payload: bytes) -> list[bytes]:
        return payload.split(b" ")

    def _request(self, payload: bytes, now: float) -> None:
        if payload == b"sRI0" or payload.startswith(b"sRI0"):
            return self._send(self._ident(b"sRA 0"))
        if len(payload) < 4 or payload[3:4] != b" ":
            return self._error(0xC)
        kind, rest = payload[:3], payload[4:]
        name, _, arg = rest.partition(b" ")
        name_s = name.decode("ascii", "replace")
        if kind == b"sRN":
            return self._read(name_s, now)
        if kind == b"sEN":
            if name_s != "LMDscandata":
                return self._error(0xF)
            on = arg[:1] == b"\x01" if self.binary else arg.strip() == b"1"
            off = arg[:1] == b"\x00" if self.binary else arg.strip() == b"0"
            if not (on or off):
                return self._error(5)
            self.streaming = on
            self._next_scan = self.device.scan_index(now) + 1
            # on a cast: the first scan is of ranges measured after the request
            self._taken, self._sent_at = now - self.device.boot, now
            return self._send(b"sEA LMDscandata " + ((b"\x01" if on else b"\x00") if self.binary
                                                     else (b"1" if on else b"0")))
        if kind == b"sMN":
            return self._method(name_s, arg)
        if kind == b"sWN":
            if name_s not in WRITABLE:
                return self._error(0xB)
            if self.access < 3:
                return self._error(0xA)
            return self._send(b"sWA " + name)
        return self._error(0xC)

    def _ident(self, head: bytes) -> bytes:
        m = self.device.model
        if self.binary:
            return (head + b" " + struct.pack(">H", len(m.name)) + m.name.encode()
                    + struct.pack(">H", len(m.firmware)) + m.firmware.encode())
        return head + f" {len(m.name):X} {m.name} {len(m.firmware):X} {m.firmware}".encode()

    def _text(self, name: str, text: str) -> bytes:
        if self.binary:
            return f"sRA {name} ".encode() + struct.pack(">H", len(text)) + text.encode()
        return f"sRA {name} {len(text):X} {text}".encode()

    def _number(self, name: str, value: int, fmt: str) -> bytes:
        if self.binary:
            return f"sRA {name} ".encode() + struct.pack(">" + fmt, value)
        return f"sRA {name} {value:X}".encode()

    def _read(self, name: str, now: float) -> None:
        m = self.device.model
        if name == "LMDscandata":
            return self._send_scan("sRA", max(self.device.scan_index(now), 0), now)
        if name == "DeviceIdent":
            return self._send(self._ident(b"sRA DeviceIdent"))
        if name == "SerialNumber":
            return self._send(self._text(name, f"{m.serial:08d}"[-8:]))
        if name == "FirmwareVersion":
            return self._send(self._text(name, m.firmware.split()[0]))
        if name == "LocationName":
            return self._send(self._text(name, "not defined"))
        if name == "SCdevicestate":
            return self._send(self._number(name, 1, "B"))
        if name == "ODoprh":
            return self._send(self._number(name, int((now - self.device.boot) / 360.0), "I"))
        if name == "ODpwrc":
            return self._send(self._number(name, 1, "I"))
        stop = m.start_angle + m.step * (m.count - 1)
        if name == "LMPoutputRange":            # sectors, resolution, start, stop (1/10000 degree)
            if self.binary:
                return self._send(b"sRA LMPoutputRange " + struct.pack(">HIii", 1, m.step, m.start_angle, stop))
            return self._send(f"sRA LMPoutputRange 1 {m.step:X} {m.start_angle & 0xFFFFFFFF:X} "
                              f"{stop & 0xFFFFFFFF:X}".encode())
        if name == "LMPscancfg":
            if self.binary:
                return self._send(b"sRA LMPscancfg " + struct.pack(">IHIii", m.frequency, 1, m.step,
                                                                   m.start_angle, stop))
            return self._send(f"sRA LMPscancfg {m.frequency:X} 1 {m.step:X} {m.start_angle & 0xFFFFFFFF:X} "
                              f"{stop & 0xFFFFFFFF:X}".encode())
        return self._error(0xB)

    def _method(self, name: str, arg: bytes) -> None:
        if name == "SetAccessMode":
            if self.binary:
                level = arg[0] if arg else 0
                password = arg[1:5].hex().upper() if len(arg) >= 5 else ""
            else:
                parts = arg.split()
                try:
                    level = int(parts[0], 16) if parts else 0
                except ValueError:
                    level = 0
                password = parts[1].decode("ascii", "replace").upper() if len(parts) > 1 else ""
            ok = PASSWORDS.get(level) == password
            if ok:
                self.access = level
            return self._send(b"sAN SetAccessMode " + ((b"\x01" if ok else b"\x00") if self.binary
                                                       else (b"1" if ok else b"0")))
        known = {"LMCstartmeas": 0, "LMCstopmeas": 0, "Run": 1, "mSCreboot": None}
        if name not in known:
            return self._error(0xB)
        if self.access < 3:
            return self._error(1)
        value = known[name]
        if value is None:
            return self._send(b"sAN " + name.encode())
        tail = bytes([value]) if self.binary else str(value).encode()
        self._send(b"sAN " + name.encode() + b" " + tail)
