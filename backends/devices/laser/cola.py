"""SICK CoLa, the telegram protocol of the TiM5xx on TCP port 2112: framing
of CoLa-A (ASCII) and CoLa-B (binary) and the ``LMDscandata`` telegram in
both (pure functions; the driver and the emulator share them).

Written from SICK's telegram listing for the TiM5xx/LMS1xx family: no
maintained Python package speaks it over TCP (``pysicktim``, last release
2019, reads a TiM561 over USB with libusb only), so it is implemented here.

* CoLa-A: ``STX`` (0x02), the telegram, ``ETX`` (0x03); fields separated by
  one blank; numbers in upper-case hex (signed ones as two's complement,
  e.g. start angle ``FFF92230`` = -450000), REAL as the 8 hex digits of the
  IEEE float (``3F800000`` = 1.0), strings with their length in front.
* CoLa-B: four ``0x02``, the payload length (uint32 big endian), the
  payload (the command as ASCII up to and with its blank, then big-endian
  binary values), then one checksum byte: XOR of the payload bytes.
* ``sRN LMDscandata`` -> ``sRA LMDscandata ...``; ``sEN LMDscandata 1`` ->
  ``sEA LMDscandata 1`` and a ``sSN LMDscandata ...`` per scan; errors
  ``sFA <code>`` (CoLa-B: ``sFA`` and the code as uint16).
* The scan telegram, field by field: version, device number, serial
  number, device status (2 bytes), telegram counter, scan counter, time
  since start-up and time of transmission (µs), digital inputs (2 bytes),
  digital outputs (2 bytes), layer angle (int16, the "reserved" field),
  scan frequency (1/100 Hz), measurement frequency (100 Hz units), number of
  encoders (+ position, speed each), number of 16-bit channels and each
  channel (content e.g. ``DIST1``, scale REAL, offset REAL, start angle
  int32 in 1/10000 degree, angular step uint16 in 1/10000 degree, number of
  values, values), number of 8-bit channels (e.g. ``RSSI1``) likewise, then
  position (0), device name (0, or 1 and a string), comment (0), time (0)
  and event info (0).  Angles are the scanner's: 90 degrees is straight
  ahead (a TiM571 scans -45 .. 225 degrees).
"""
from __future__ import annotations

import struct
from dataclasses import dataclass, field

STX, ETX = 0x02, 0x03
B_MAGIC = b"\x02\x02\x02\x02"
MAX_TELEGRAM = 1 << 20

#: SOPAS error codes of ``sFA`` answers
ERRORS = {
    1: "METHODIN_ACCESSDENIED", 2: "METHODIN_UNKNOWNINDEX", 3: "VARIABLE_UNKNOWNINDEX",
    4: "LOCALCONDITIONFAILED", 5: "INVALID_DATA", 6: "UNKNOWN_ERROR", 7: "BUFFER_OVERFLOW",
    8: "BUFFER_UNDERFLOW", 9: "ERROR_UNKNOWN_TYPE", 0xA: "VARIABLE_WRITE_ACCESSDENIED",
    0xB: "UNKNOWN_CMD_FOR_NAMESERVER", 0xC: "UNKNOWN_COLA_COMMAND", 0xD: "METHODIN_SERVER_BUSY",
    0xE: "FLEX_OUT_OF_BOUNDS", 0xF: "EVENTREG_UNKNOWNINDEX", 0x10: "COLA_A_VALUE_OVERFLOW",
    0x11: "COLA_A_INVALID_CHARACTER", 0x12: "OSAI_NO_MESSAGE", 0x13: "OSAI_NO_ANSWER_MESSAGE",
    0x14: "INTERNAL", 0x15: "HubAddressCorrupted", 0x16: "HubAddressDecoding",
    0x17: "HubAddressAddressExceeded", 0x18: "HubAddressBlankExpected", 0x19: "AsyncMethodsAreSuppressed",
    0x1A: "ComplexArraysNotSupported",
}


class ColaError(ValueError):
    """A telegram that breaks the protocol."""


# -- framing -----------------------------------------------------------------------

def frame_a(telegram: bytes) -> bytes:
    if STX in telegram or ETX in telegram:
        raise ValueError("a CoLa-A telegram cannot contain STX or ETX")
    return bytes([STX]) + telegram + bytes([ETX])


def xor(data: bytes) -> int:
    x = 0
    for b in data:
        x ^= b
    return x


def frame_b(payload: bytes) -> bytes:
    return B_MAGIC + struct.pack(">I", len(payload)) + payload + bytes([xor(payload)])


@dataclass
class Telegram:
    payload: bytes
    binary: bool

    @property
    def kind(self) -> str:
        """``sRA``, ``sSN``, ``sFA``..."""
        return self.payload[:3].decode("ascii", "replace")

    @property
    def name(self) -> str:
        rest = self.payload[4:]
        return rest.split(b" ", 1)[0].decode("ascii", "replace")


class TelegramReader:
    """Splits a byte stream into telegrams of either dialect.  Bytes
    outside a frame are skipped (counted); a CoLa-B frame with a wrong
    checksum is dropped (counted)."""

    def __init__(self, max_size: int = MAX_TELEGRAM):
        self.max_size = max_size
        self._buf = bytearray()
        self.skipped = 0
        self.checksum_errors = 0

    def reset(self) -> None:
        self._buf.clear()

    def feed(self, data: bytes) -> list[Telegram]:
        self._buf += data
        out = []
        buf = self._buf
        while buf:
            if buf[0] != STX:
                i = buf.find(bytes([STX]))
                n = len(buf) if i < 0 else i
                self.skipped += n
                del buf[:n]
                continue
            if len(buf) < 2:
                break
            if buf[1] == STX:                        # CoLa-B (or garbage)
                if len(buf) < 8:
                    if len(buf) >= 4 and buf[:4] != B_MAGIC:
                        self.skipped += 1
                        del buf[:1]
                        continue
                    break
                (length,) = struct.unpack(">I", buf[4:8])
                if buf[:4] != B_MAGIC or length > self.max_size:
                    self.skipped += 1
                    del buf[:1]
                    continue
                if len(buf) < 9 + length:
                    break
                payload = bytes(buf[8:8 + length])
                check = buf[8 + length]
                del buf[:9 + length]
                if xor(payload) != check:
                    self.checksum_errors += 1
                    continue
                out.append(Telegram(payload, True))
                continue
            end = buf.find(bytes([ETX]), 1)
            if end < 0:
                if len(buf) > self.max_size:
                    self.skipped += len(buf)
                    buf.clear()
                break
            cut = buf.find(bytes([STX]), 1, end)
            if cut >= 0:                             # a new STX before the end: the one before was cut short
                self.skipped += cut
                del buf[:cut]
                continue
            out.append(Telegram(bytes(buf[1:end]), False))
            del buf[:end + 1]
        return out


# -- the scan telegram ---------------------------------------------------------------

@dataclass
class Channel:
    content: str                  # "DIST1", "RSSI1"...
    scale: float
    offset: float
    start_angle: int              # 1/10000 degree
    step: int                     # 1/10000 degree
    data: list[int]


@dataclass
class ScanData:
    version: int = 1
    device: int = 1
    serial: int = 0
    status: tuple[int, int] = (0, 0)
    telegram_counter: int = 0
    scan_counter: int = 0
    time_since_startup: int = 0          # µs
    time_of_transmission: int = 0        # µs
    inputs: tuple[int, int] = (0, 0)
    outputs: tuple[int, int] = (0, 0)
    layer_angle: int = 0
    scan_frequency: int = 1500           # 1/100 Hz
    measurement_frequency: int = 162     # 100 Hz units
    encoders: list[tuple[int, int]] = field(default_factory=list)
    channels16: list[Channel] = field(default_factory=list)
    channels8: list[Channel] = field(default_factory=list)
    name: str | None = None

    def channel(self, content: str) -> Channel | None:
        for c in self.channels16 + self.channels8:
            if c.content == content:
                return c
        return None


def _real_hex(v: float) -> str:
    return struct.pack(">f", v).hex().upper()


def _hex(v: int) -> str:
    return f"{v:X}"


def _s32(v: int) -> str:
    return f"{v & 0xFFFFFFFF:X}"


def encode_scan_a(kind: str, s: ScanData) -> bytes:
    """``sRA``/``sSN LMDscandata`` as CoLa-A (without STX/ETX)."""
    t = [kind, "LMDscandata", _hex(s.version), _hex(s.device), _hex(s.serial), *map(_hex, s.status),
         _hex(s.telegram_counter), _hex(s.scan_counter), _hex(s.time_since_startup), _hex(s.time_of_transmission),
         *map(_hex, s.inputs), *map(_hex, s.outputs), f"{s.layer_angle & 0xFFFF:X}", _hex(s.scan_frequency),
         _hex(s.measurement_frequency), _hex(len(s.encoders))]
    for pos, speed in s.encoders:
        t += [_hex(pos), _hex(speed)]
    for group in (s.channels16, s.channels8):
        t.append(_hex(len(group)))
        for c in group:
            t += [c.content, _real_hex(c.scale), _real_hex(c.offset), _s32(c.start_angle), _hex(c.step),
                  _hex(len(c.data)), *map(_hex, c.data)]
    t.append("0")                                  # position
    if s.name:
        t += ["1", _hex(len(s.name)), s.name]
    else:
        t.append("0")
    t += ["0", "0", "0"]                           # comment, time, event info
    return " ".join(t).encode("ascii")


def encode_scan_b(kind: str, s: ScanData) -> bytes:
    """The same as a CoLa-B payload (without the frame)."""
    out = bytearray(f"{kind} LMDscandata ".encode())
    out += struct.pack(">HHIBBHHIIBBBBhII", s.version, s.device, s.serial, *s.status, s.telegram_counter,
                       s.scan_counter, s.time_since_startup, s.time_of_transmission, *s.inputs, *s.outputs,
                       s.layer_angle, s.scan_frequency, s.measurement_frequency)
    out += struct.pack(">H", len(s.encoders))
    for pos, speed in s.encoders:
        out += struct.pack(">IH", pos, speed)
    for group, fmt in ((s.channels16, "H"), (s.channels8, "B")):
        out += struct.pack(">H", len(group))
        for c in group:
            out += c.content.encode("ascii")[:5].ljust(5, b" ")
            out += struct.pack(">ffiHH", c.scale, c.offset, c.start_angle, c.step, len(c.data))
            out += struct.pack(f">{len(c.data)}{fmt}", *c.data)
    out += struct.pack(">H", 0)
    if s.name:
        out += struct.pack(">HH", 1, len(s.name)) + s.name.encode("ascii")
    else:
        out += struct.pack(">H", 0)
    out += struct.pack(">HHH", 0, 0, 0)
    return bytes(out)


class _Tokens:
    def __init__(self, text: bytes):
        self.t = text.split(b" ")
        self.i = 0

    def next(self) -> bytes:
        if self.i >= len(self.t):
            raise ColaError("scan telegram ends too early")
        v = self.t[self.i]
        self.i += 1
        return v

    def hex(self, bits: int = 32, signed: bool = False) -> int:
        tok = self.next()
        try:
            if tok[:1] in (b"+", b"-"):        # some firmwares send signed decimals
                v = int(tok)
            else:
                v = int(tok, 16)
        except ValueError:
            raise ColaError(f"{tok[:20]!r} is not a number") from None
        if v < 0 and not signed:
            raise ColaError(f"{tok!r} is negative")
        if v >= 1 << bits and tok[:1] not in (b"+", b"-"):
            raise ColaError(f"{tok!r} does not fit in {bits} bits")
        if signed and v >= 1 << (bits - 1):
            v -= 1 << bits
        return v

    def real(self) -> float:
        tok = self.next()
        if len(tok) != 8:
            raise ColaError(f"REAL {tok!r} is not 8 hex digits")
        try:
            return struct.unpack(">f", bytes.fromhex(tok.decode("ascii")))[0]
        except ValueError:
            raise ColaError(f"REAL {tok!r} is not hex") from None


def decode_scan_a(telegram: bytes) -> ScanData:
    """A CoLa-A ``sRA``/``sSN LMDscandata`` telegram (without STX/ETX)."""
    tk = _Tokens(telegram)
    kind, name = tk.next(), tk.next()
    if kind not in (b"sRA", b"sSN") or name != b"LMDscandata":
        raise ColaError(f"not a scan telegram: {telegram[:40]!r}")
    s = ScanData()
    s.version, s.device, s.serial = tk.hex(16), tk.hex(16), tk.hex(32)
    s.status = (tk.hex(8), tk.hex(8))
    s.telegram_counter, s.scan_counter = tk.hex(16), tk.hex(16)
    s.time_since_startup, s.time_of_transmission = tk.hex(32), tk.hex(32)
    s.inputs = (tk.hex(8), tk.hex(8))
    s.outputs = (tk.hex(8), tk.hex(8))
    s.layer_angle = tk.hex(16, signed=True)
    s.scan_frequency, s.measurement_frequency = tk.hex(32), tk.hex(32)
    s.encoders = [(tk.hex(32), tk.hex(16)) for _ in range(tk.hex(16))]
    for group, bits in ((s.channels16, 16), (s.channels8, 8)):
        for _ in range(tk.hex(16)):
            content = tk.next().decode("ascii", "replace")
            scale, offset = tk.real(), tk.real()
            start, step, n = tk.hex(32, signed=True), tk.hex(16), tk.hex(16)
            group.append(Channel(content, scale, offset, start, step, [tk.hex(bits) for _ in range(n)]))
    return s


def decode_scan_b(payload: bytes) -> ScanData:
    """A CoLa-B ``sRA``/``sSN LMDscandata`` payload."""
    head = b"LMDscandata "
    if payload[:4] not in (b"sRA ", b"sSN ") or payload[4:4 + len(head)] != head:
        raise ColaError(f"not a scan telegram: {payload[:40]!r}")
    data = memoryview(payload)[4 + len(head):]
    pos = 0

    def take(fmt):
        nonlocal pos
        size = struct.calcsize(fmt)
        if pos + size > len(data):
            raise ColaError("scan telegram ends too early")
        v = struct.unpack_from(fmt, data, pos)
        pos += size
        return v

    s = ScanData()
    (s.version, s.device, s.serial, st0, st1, s.telegram_counter, s.scan_counter, s.time_since_startup,
     s.time_of_transmission, i0, i1, o0, o1, s.layer_angle, s.scan_frequency,
     s.measurement_frequency) = take(">HHIBBHHIIBBBBhII")
    s.status, s.inputs, s.outputs = (st0, st1), (i0, i1), (o0, o1)
    (n,) = take(">H")
    s.encoders = [take(">IH") for _ in range(n)]
    for group, fmt in ((s.channels16, "H"), (s.channels8, "B")):
        (n,) = take(">H")
        for _ in range(n):
            (content,) = take(">5s")
            scale, offset, start, step, count = take(">ffiHH")
            values = list(take(f">{count}{fmt}"))
            group.append(Channel(content.decode("ascii", "replace").strip(), scale, offset, start, step, values))
    return s


def error_answer(code: int, binary: bool) -> bytes:
    return b"sFA" + struct.pack(">H", code) if binary else f"sFA {code:X}".encode()


def error_code(t: Telegram) -> int | None:
    """The SOPAS error code of an ``sFA`` answer, else None."""
    if t.kind != "sFA":
        return None
    if t.binary:
        tail = t.payload[3:]
        if len(tail) >= 2:
            return struct.unpack(">H", tail[:2])[0]
        return tail[0] if tail else 0
    try:
        return int(t.payload[4:].strip() or b"0", 16)
    except ValueError:
        return 0x14
