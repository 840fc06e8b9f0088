"""SICK TiM5xx driver: CoLa-A or CoLa-B telegrams over TCP (port 2112).

    laser = TimLaser("192.168.0.1", mount=LaserMount(x=0.2)).start(wait=2.0)

On connect: ``sMN SetAccessMode 03 F4724744`` (authorised client; a refusal
is only logged), ``sRN DeviceIdent``, then ``sEN LMDscandata 1`` (``mode=
"stream"``) or one ``sRN LMDscandata`` per scan period (``mode="poll"``).
``dialect`` is ``"a"`` (ASCII, the default) or ``"b"`` (binary frames with
their XOR checksum).  A scan's ``DIST1`` channel becomes the ranges
(``value * scale + offset`` mm, 0 = no echo -> ``inf``), its angles the
scanner's minus 90 degrees (the TiM looks along its 90 degree axis); the
device's microsecond stamp (time since start-up, 32 bits) is mapped to the
host clock (:class:`~.stamps.DeviceClock`).  ``sFA`` answers are counted as
device errors.  Reconnects as :class:`~.base.LaserDriver` says.  The codec
is :mod:`.cola` (why it is written here is said there).
"""
from __future__ import annotations

import math
import select
import socket

import numpy as np

from rll_bt.backend import LaserScan

from . import cola
from .base import LaserDriver, LinkLost
from .stamps import DeviceClock

DEFAULT_PORT = 2112


class TimLaser(LaserDriver):
    kind = "tim"

    def __init__(self, host: str, port: int = DEFAULT_PORT, *, mode: str = "stream", dialect: str = "a",
                 range_limits: tuple[float, float] = (0.05, 25.0), reply_timeout: float = 1.0,
                 scan_period: float = 1.0 / 15.0, **options):
        if mode not in ("stream", "poll"):
            raise ValueError(f"mode must be 'stream' or 'poll', not {mode!r}")
        if dialect not in ("a", "b"):
            raise ValueError(f"dialect must be 'a' (CoLa-A) or 'b' (CoLa-B), not {dialect!r}")
        super().__init__(**options)
        self.host, self.port = host, int(port)
        self.mode, self.dialect = mode, dialect
        self.range_limits = range_limits
        self.reply_timeout = reply_timeout
        self.scan_period = scan_period
        self._sock: socket.socket | None = None
        self._reader = cola.TelegramReader()
        self._clock = DeviceClock(1 << 32, 1e-6)
        self._next_poll = 0.0
        self.access_granted = False

    def describe(self) -> str:
        return f"TiM at {self.host}:{self.port}"

    # -- link ----------------------------------------------------------------------
    def _send(self, ascii_payload: bytes, binary_payload: bytes | None = None) -> None:
        if self._sock is None:
            raise LinkLost("not connected")
        if self.dialect == "a":
            frame = cola.frame_a(ascii_payload)
        else:
            frame = cola.frame_b(binary_payload if binary_payload is not None else ascii_payload)
        self._sock.sendall(frame)

    def _telegrams(self, timeout: float) -> list[cola.Telegram]:
        sock = self._sock
        if sock is None:
            raise LinkLost("not connected")
        ready, _, _ = select.select([sock], [], [], timeout)
        if not ready:
            return []
        data = sock.recv(1 << 16)
        if not data:
            raise LinkLost("connection closed by the scanner")
        return self._reader.feed(data)

    def _await(self, kind: str, name: str) -> cola.Telegram:
        end = self.clock.now() + self.reply_timeout
        while self.clock.now() < end:
            for t in self._telegrams(0.02):
                if t.kind == "sFA":
                    return t
                if t.kind == kind and t.name == name:
                    return t
        raise LinkLost(f"no {kind} {name} within {self.reply_timeout:g} s")

    def _connect(self) -> None:
        try:
            self._sock = socket.create_connection((self.host, self.port), timeout=self.reply_timeout)
        except OSError as exc:
            raise LinkLost(f"cannot connect: {exc}") from None
        self._sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        self._reader.reset()
        self._send(b"sMN SetAccessMode 03 F4724744", b"sMN SetAccessMode \x03\xf4\x72\x47\x44")
        reply = self._await("sAN", "SetAccessMode")
        self.access_granted = reply.kind == "sAN" and reply.payload.rstrip()[-1:] in (b"1", b"\x01")
        self._send(b"sRN DeviceIdent")
        ident = self._await("sRA", "DeviceIdent")
        if ident.kind == "sRA":
            self.info["DeviceIdent"] = _ident_text(ident)
        self._clock.reset()
        if self.mode == "stream":
            self._send(b"sEN LMDscandata 1", b"sEN LMDscandata \x01")
            reply = self._await("sEA", "LMDscandata")
            if reply.kind == "sFA":
                raise LinkLost(f"sEN LMDscandata refused: {cola.ERRORS.get(cola.error_code(reply), '?')}")
        self._next_poll = self.clock.now()

    def _disconnect(self) -> None:
        sock, self._sock = self._sock, None
        if sock is not None:
            try:
                if self.mode == "stream":
                    sock.sendall(cola.frame_a(b"sEN LMDscandata 0") if self.dialect == "a"
                                 else cola.frame_b(b"sEN LMDscandata \x00"))
            except OSError:
                pass
            sock.close()

    # -- scans ----------------------------------------------------------------------
    def _read(self, timeout: float) -> list[LaserScan]:
        if self.mode == "poll":
            now = self.clock.now()
            if now >= self._next_poll:
                self._send(b"sRN LMDscandata")
                self._next_poll = max(now, self._next_poll) + self.scan_period
            timeout = min(timeout, max(0.0, self._next_poll - now))
        out = []
        for t in self._telegrams(timeout):
            received = self.clock.now()
            if t.kind == "sFA":
                self._error(f"device error {cola.ERRORS.get(cola.error_code(t), '?')}", device=True)
                continue
            if t.name != "LMDscandata" or t.kind not in ("sRA", "sSN"):
                continue
            try:
                data = cola.decode_scan_b(t.payload) if t.binary else cola.decode_scan_a(t.payload)
                out.append(self._to_scan(data, received))
            except cola.ColaError as exc:
                self._error(str(exc))
        return out

    def _to_scan(self, s: cola.ScanData, received: float) -> LaserScan:
        ch = s.channel("DIST1")
        if ch is None or not ch.data:
            raise cola.ColaError("scan without a DIST1 channel")
        mm = np.asarray(ch.data, dtype=float) * ch.scale + ch.offset
        lo, hi = self.range_limits
        m = mm / 1000.0
        ranges = np.where((np.asarray(ch.data) > 0) & (m >= lo) & (m <= hi), m, np.inf)
        angle_min = math.radians(ch.start_angle / 10000.0 - 90.0)
        increment = math.radians(ch.step / 10000.0)
        stamp = self._clock.to_host(s.time_since_startup, received)
        return self.mount.scan(stamp, angle_min, increment, ranges, lo, hi)


def _ident_text(t: cola.Telegram) -> str:
    """"TiM571 V3.32 ..." from a DeviceIdent answer (two length-prefixed strings)."""
    body = t.payload[len(b"sRA DeviceIdent "):]
    if t.binary:
        parts, i = [], 0
        while i + 2 <= len(body) and len(parts) < 2:
            n = int.from_bytes(body[i:i + 2], "big")
            parts.append(body[i + 2:i + 2 + n].decode("ascii", "replace"))
            i += 2 + n
        return " ".join(parts)
    tokens = body.decode("ascii", "replace").split(" ")
    return " ".join(tok for k, tok in enumerate(tokens) if k not in (0, 2))
