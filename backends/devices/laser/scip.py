"""SCIP 2.0, the Hokuyo URG text protocol: encoding, checksums, lines and
response blocks (pure functions, no I/O; both the driver and the emulator
use them).

Written from the vendor's "Communication Protocol Specification for
SCIP2.0" (C-42-03320B) and the URG-04LX / UTM-30LX listings.  No maintained
Python library does this over a serial line: ``hokuyolx`` (last release
2016) speaks SCIP over TCP to the UST series only and cannot switch an
URG-04LX out of SCIP 1.1, so the protocol is implemented here.

Facts used:

* a command is a line: 2-letter symbol, parameters, an optional string of
  at most 16 characters after ``;`` (letters, digits, blank, ``.``, ``_``,
  ``+``, ``@``), ended by LF, CR or both;
* a reply is a block: the echoed command line, a status line (2 characters
  and their checksum, e.g. ``00P``, ``99b``), data lines, and an empty line
  (so it ends with two LFs); SCIP 1.1 answers with a 1-character status;
* the checksum of a line is ``(sum of its bytes & 0x3F) + 0x30``; for the
  ``NAME:value;S`` lines of VV/PP/II it covers the text before ``;``;
* values are 2, 3 or 4 characters of 6 bits each (+0x30), most significant
  first; data lines carry at most 64 characters plus their checksum and a
  value may span two lines; time stamps are 4 characters (24-bit ms);
* statuses: 00 ok, 99 scan data of MD/MS; 0A..0I malformed or unknown
  commands (0E: undefined command); 01..07 bad parameters of GD/MD; 10
  laser off (GD); 50..97 hardware trouble.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

OFFSET = 0x30
LINE_WIDTH = 64
STRING_CHARS = frozenset(b"abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789 ._+@")
MAX_STRING = 16

#: statuses a URG sends (spec section 8 and 9)
STATUS_TEXT = {
    "00": "ok", "99": "scan data",
    "01": "start step not numeric (or laser malfunction for BM)", "02": "end step not numeric (or laser already on)",
    "03": "cluster count not numeric", "04": "end step out of range", "05": "end step smaller than start step",
    "06": "scan interval not numeric", "07": "number of scans not numeric", "10": "laser is off",
    "0A": "cannot create the reply", "0B": "buffer shortage or command repeated",
    "0C": "insufficient parameters", "0D": "undefined command", "0E": "undefined command",
    "0F": "insufficient parameters", "0G": "string longer than 16 characters",
    "0H": "string has invalid characters", "0I": "sensor in firmware update mode",
}


class ScipError(ValueError):
    """A reply that breaks the protocol (checksum, framing, values)."""


def checksum(data: bytes) -> int:
    """The SCIP sum character of ``data``."""
    return (sum(data) & 0x3F) + OFFSET


def sum_line(body: bytes) -> bytes:
    """``body`` + its checksum character + LF."""
    return body + bytes([checksum(body)]) + b"\n"


def info_line(name: str, value: str) -> bytes:
    """A ``NAME:value;S`` line of VV/PP/II (checksum before the ``;``)."""
    text = f"{name}:{value}".encode("ascii")
    return text + b";" + bytes([checksum(text)]) + b"\n"


def encode(value: int, size: int) -> bytes:
    """``value`` (0 .. 2**(6*size)-1) as ``size`` characters."""
    if not 0 <= value < 1 << (6 * size):
        raise ValueError(f"{value} does not fit in {size} SCIP characters")
    return bytes(OFFSET + (value >> (6 * (size - 1 - i)) & 0x3F) for i in range(size))


def decode(chars: bytes) -> int:
    """The value of SCIP characters (any length)."""
    value = 0
    for c in chars:
        d = c - OFFSET
        if not 0 <= d < 64:
            raise ScipError(f"character {chr(c)!r} is not a SCIP digit")
        value = value << 6 | d
    return value


def encode_values(values, size: int) -> bytes:
    """Every value as ``size`` characters, one array operation for a whole scan
    (the same bytes as :func:`encode` value by value)."""
    v = np.asarray(values, dtype=np.int64).reshape(-1)
    bad = (v < 0) | (v >= 1 << (6 * size))
    if bad.any():
        raise ValueError(f"{int(v[bad][0])} does not fit in {size} SCIP characters")
    shifts = 6 * np.arange(size - 1, -1, -1, dtype=np.int64)
    return ((v[:, None] >> shifts & 0x3F) + OFFSET).astype(np.uint8).tobytes()


def decode_values(data: bytes, size: int) -> list[int]:
    """The values of a data block's characters (as :func:`decode` each group of ``size``)."""
    if len(data) % size:
        raise ScipError(f"{len(data)} data characters are not a multiple of {size}")
    d = np.frombuffer(data, dtype=np.uint8).astype(np.int64) - OFFSET
    bad = (d < 0) | (d >= 64)
    if bad.any():
        raise ScipError(f"character {chr(d[bad][0] + OFFSET)!r} is not a SCIP digit")
    digits = d.reshape(-1, size)
    return (digits << (6 * np.arange(size - 1, -1, -1, dtype=np.int64))).sum(axis=1).tolist()


def data_block(payload: bytes) -> bytes:
    """``payload`` cut into lines of 64 characters, each with its sum."""
    return b"".join(sum_line(payload[i:i + LINE_WIDTH]) for i in range(0, len(payload), LINE_WIDTH))


def status_line(status: str) -> bytes:
    return sum_line(status.encode("ascii"))


@dataclass
class Block:
    """One reply: the echo and the lines after it (without LFs, the empty
    line that ends the block left out)."""
    echo: bytes
    lines: list[bytes] = field(default_factory=list)

    @property
    def command(self) -> str:
        return self.echo[:2].decode("ascii", "replace")

    @property
    def status(self) -> str:
        """The status ("00", "99"...; one character in SCIP 1.1); checked."""
        if not self.lines:
            raise ScipError(f"reply to {self.echo!r} has no status line")
        line = self.lines[0]
        if len(line) == 1:                      # SCIP 1.1
            return line.decode("ascii", "replace")
        if len(line) != 3 or line[2] != checksum(line[:2]):
            raise ScipError(f"bad status line {line!r} in the reply to {self.echo!r}")
        return line[:2].decode("ascii", "replace")

    def info(self) -> dict[str, str]:
        """``NAME: value`` of the VV/PP/II lines (checksums checked)."""
        out = {}
        for line in self.lines[1:]:
            text, sep, s = line.rpartition(b";")
            if not sep or len(s) != 1 or s[0] != checksum(text):
                raise ScipError(f"bad information line {line!r}")
            name, colon, value = text.partition(b":")
            if not colon:
                raise ScipError(f"information line without a name: {line!r}")
            out[name.decode("ascii", "replace")] = value.decode("ascii", "replace")
        return out

    def scan(self, size: int) -> tuple[int, list[int]]:
        """(time stamp, values) of a GD/GS/MD/MS data block; checksums checked."""
        if len(self.lines) < 2:
            raise ScipError(f"scan reply to {self.echo!r} without a time stamp")
        stamp = self.lines[1]
        if len(stamp) != 5 or stamp[4] != checksum(stamp[:4]):
            raise ScipError(f"bad time stamp line {stamp!r}")
        data = bytearray()
        for line in self.lines[2:]:
            if len(line) < 2 or len(line) > LINE_WIDTH + 1 or line[-1] != checksum(line[:-1]):
                raise ScipError(f"bad data line {line[:70]!r}")
            data += line[:-1]
        return decode(stamp[:4]), decode_values(bytes(data), size)


class BlockReader:
    """Splits a byte stream into reply blocks (an empty line ends one).
    CRs are dropped; a line longer than ``max_line`` is a framing error."""

    def __init__(self, max_line: int = 256):
        self.max_line = max_line
        self._buf = bytearray()
        self._lines: list[bytes] = []
        self.framing_errors = 0

    def reset(self) -> None:
        self._buf.clear()
        self._lines = []

    def feed(self, data: bytes) -> list[Block]:
        out = []
        self._buf += data
        while True:
            i = self._buf.find(b"\n")
            if i < 0:
                if len(self._buf) > self.max_line:
                    self.framing_errors += 1
                    self.reset()
                break
            line = bytes(self._buf[:i]).replace(b"\r", b"")
            del self._buf[:i + 1]
            if len(line) > self.max_line:
                self.framing_errors += 1
                self._lines = []
                continue
            if line:
                self._lines.append(line)
            elif self._lines:
                out.append(Block(self._lines[0], self._lines[1:]))
                self._lines = []
        return out


def command(symbol: str, params: str = "", tag: str = "") -> bytes:
    """A command line, with ``tag`` as its string characters (``;tag``)."""
    if tag and (len(tag) > MAX_STRING or not set(tag.encode()) <= STRING_CHARS):
        raise ValueError(f"SCIP string {tag!r}: at most 16 letters, digits, blank, '.', '_', '+', '@'")
    return f"{symbol}{params}{';' + tag if tag else ''}\n".encode("ascii")


def scan_command(symbol: str, start: int, end: int, cluster: int = 1, interval: int | None = None,
                 scans: int | None = None, tag: str = "") -> bytes:
    """GD/GS (``interval``/``scans`` None) or MD/MS parameters."""
    params = f"{start:04d}{end:04d}{cluster:02d}"
    if interval is not None:
        params += f"{interval:01d}{scans or 0:02d}"
    return command(symbol, params, tag)
