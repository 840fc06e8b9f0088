"""The Carologistics RCLL gripper's ASCII protocol (Arduino, 115200 8N1).

Host -> Arduino: ``"AT "`` then items ``<cmd><unsigned decimal> `` (each with
a trailing space), ended by ``'+'``; no newline, no checksum::

    AT X120 Y300 Z0 +

Arduino -> host: lines ending in ``\\r\\n``::

    AT HELLO +116
    AT I 0 0 0 0 CLOSED+<cksum>      (status M moving, I idle, E error)
    AT E <message>+<cksum>

``cksum`` is the decimal value of the sum of the character codes from the
'A' of ``"AT "`` up to and including the '+', modulo 256.  The sketch does
not count an error message's text (it adds a constant meant for the five
spaces of a status line), so error lines carry a checksum of
``(ord('E') + 128) % 256 == 197`` whatever the text; :func:`parse_line`
accepts an error line whose checksum is the full sum, that constant, or the
sum without the text.  Positions are stepper steps as the host commanded
them (the sketch negates its internal counts back).
"""
from __future__ import annotations

import math
from collections.abc import Iterable
from dataclasses import dataclass

TERMINATOR = "+"
PREFIX = "AT "

# command letters (each carries an unsigned number, 0 when unused)
CALIBRATE, DOUBLE_CALIBRATE, CALIBRATE_X = "C", "c", "r"
MOVE_X, MOVE_Y, MOVE_Z = "X", "Y", "Z"
CLOSE, OPEN = "G", "O"
STOP, FAST_STOP, STATUS = ".", ":", "S"
TOGGLE_STEPS = "T"
SPEED_X, SPEED_Y, SPEED_Z, SPEED_A, SPEED_ALL = "x", "y", "z", "a", "b"
ACCEL_X, ACCEL_Y, ACCEL_Z, ACCEL_A, ACCEL_ALL = "m", "n", "o", "p", "q"

COMMANDS = frozenset("CcrXYZGO.:STxyzabmnopq")

#: the sketch's checksum of an error line (it skips the message text)
FIRMWARE_ERROR_CHECKSUM = (ord("E") + 128) % 256


def encode_command(items: Iterable[tuple[str, int]]) -> bytes:
    """``[("X", 120), ("Y", 300)]`` -> ``b"AT X120 Y300 +"``."""
    parts = []
    for cmd, value in items:
        if cmd not in COMMANDS:
            raise ValueError(f"unknown gripper command {cmd!r}")
        if not isinstance(value, int) or value < 0:
            raise ValueError(f"gripper command {cmd!r} needs an unsigned integer, got {value!r}")
        parts.append(f"{cmd}{value} ")
    if not parts:
        raise ValueError("a gripper message needs at least one command")
    return (PREFIX + "".join(parts) + TERMINATOR).encode("ascii")


def line_checksum(text: str) -> int:
    """Sum of the character codes of ``text`` mod 256 (``text`` runs from
    the 'A' of "AT " through the '+')."""
    return sum(text.encode("latin-1", "replace")) % 256


def with_checksum(body: str) -> bytes:
    """``body`` (from "AT " through '+') plus checksum digits and CR LF."""
    return f"{body}{line_checksum(body)}\r\n".encode("latin-1", "replace")


def status_line(state: str, x: int, y: int, z: int, is_open: bool, a: int = 0) -> bytes:
    """A complete status line as the sketch prints it (state 'M' or 'I')."""
    return with_checksum(f"AT {state} {x} {y} {z} {a} {'OPEN' if is_open else 'CLOSED'}+")


def hello_line() -> bytes:
    return with_checksum("AT HELLO +")


def error_line(message: str) -> bytes:
    """An error line with the sketch's own (text-blind) checksum."""
    return f"AT E {message}+{FIRMWARE_ERROR_CHECKSUM}\r\n".encode("latin-1", "replace")


@dataclass(frozen=True)
class GripperMessage:
    """A line that passed its checksum.  ``kind`` is ``"hello"`` or
    ``"status"``; ``state`` 'M', 'I' or 'E'; ``position`` in steps."""
    kind: str
    state: str = ""
    position: tuple[int, int, int] = (0, 0, 0)
    a: int = 0
    is_open: bool | None = None
    text: str = ""


@dataclass(frozen=True)
class Rejected:
    """A line that is not a valid message, and why."""
    reason: str
    line: str = ""


def parse_line(line: bytes | str) -> GripperMessage | Rejected:
    """Check and parse one line (with or without the CR LF).  Never raises."""
    text = line.decode("latin-1") if isinstance(line, (bytes, bytearray)) else str(line)
    text = text.rstrip("\r\n")
    start = text.find(PREFIX)
    if start < 0:
        return Rejected("no 'AT ' in line", text)
    end = text.rfind(TERMINATOR)
    if end < start + len(PREFIX):
        return Rejected("no '+' terminator", text)
    body, digits = text[start:end + 1], text[end + 1:].strip()
    if not (digits.isascii() and digits.isdigit()) or len(digits) > 3:
        return Rejected(f"bad checksum digits {digits!r}", text)
    got = int(digits)
    inner = body[len(PREFIX):-1]
    if inner.startswith("E"):
        message = inner[1:].strip()
        allowed = {line_checksum(body), FIRMWARE_ERROR_CHECKSUM,
                   line_checksum(PREFIX + "E " + TERMINATOR)}
        if got not in allowed:
            return Rejected(f"checksum {got} does not match error line", text)
        return GripperMessage("status", "E", text=message)
    want = line_checksum(body)
    if got != want:
        return Rejected(f"checksum {got} != {want}", text)
    tokens = inner.split()
    if tokens == ["HELLO"]:
        return GripperMessage("hello")
    if len(tokens) != 6 or tokens[0] not in ("M", "I") or tokens[5] not in ("OPEN", "CLOSED"):
        return Rejected(f"unexpected status fields {tokens!r}", text)
    try:
        x, y, z, a = (int(t) for t in tokens[1:5])
    except ValueError:
        return Rejected(f"non-integer position in {tokens!r}", text)
    return GripperMessage("status", tokens[0], (x, y, z), a, tokens[5] == "OPEN")


class LineSplitter:
    """Cut a byte stream into CR LF terminated lines; a line longer than
    ``max_line`` bytes is dropped (counted in ``overflows``)."""

    def __init__(self, max_line: int = 512):
        self.max_line = max_line
        self.overflows = 0
        self._buf = bytearray()

    def reset(self) -> None:
        self._buf.clear()

    def feed(self, data: bytes) -> list[bytes]:
        self._buf.extend(data)
        lines = []
        while True:
            i = self._buf.find(b"\r\n")
            if i < 0:
                break
            lines.append(bytes(self._buf[:i]))
            del self._buf[:i + 2]
        if len(self._buf) > self.max_line:
            self.overflows += 1
            self._buf.clear()
        return lines


@dataclass(frozen=True)
class StepsPerMetre:
    """Axis scale (steps per metre).  Carologistics config: steps/mm are
    X = 200 * ustep / 44, Y = 200 * ustep / 2, Z = 200 * ustep / 1.5 with
    ustep = 2."""
    x: float = 200.0 * 2 / 44 * 1000.0
    y: float = 200.0 * 2 / 2 * 1000.0
    z: float = 200.0 * 2 / 1.5 * 1000.0

    def to_steps(self, x: float, y: float, z: float) -> tuple[int, int, int]:
        """Metres -> steps (rounded); ValueError for negative or non-finite."""
        out = []
        for name, v, scale in (("x", x, self.x), ("y", y, self.y), ("z", z, self.z)):
            if not math.isfinite(v) or v < 0:
                raise ValueError(f"gripper {name} = {v!r} m: must be a finite value >= 0")
            out.append(int(round(v * scale)))
        return tuple(out)  # type: ignore[return-value]

    def to_metres(self, steps: tuple[int, int, int]) -> tuple[float, float, float]:
        return (steps[0] / self.x, steps[1] / self.y, steps[2] / self.z)
