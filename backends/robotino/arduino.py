"""A model of the Carologistics gripper sketch (Arduino side of the link).

Pure logic: :meth:`GripperFirmware.reset` is the power-up that happens when
the host opens the port (HELLO, a status line, then homing),
:meth:`receive` takes host bytes, :meth:`advance` moves the axes; each
returns the bytes the sketch prints.  Behaviour as in the fact sheet:

* a status line after S, stop (``.``), the speed/accel/toggle commands, and
  whenever the status (M/I/E) changes; none after X/Y/Z/O/G themselves;
* while moving, a status line every ``moving_report_period`` seconds;
* commands are parsed like the sketch: buffer up to '+', find ``"AT "``,
  each command letter followed by a number (``%ld``), next command after the
  next space; a malformed number drops the rest of the message;
* an error (:meth:`fail`) prints ``AT E <message>+197``.

Boot: the board's bootloader runs for ``boot_time`` seconds after the reset
before the sketch starts and prints HELLO; bytes sent to it meanwhile are
lost (as on a real Arduino, and the host's flush of its input on open cannot
swallow HELLO).

Simplifications: axes move at constant speed (steps/s), homing drives all
axes to 0 and takes at least ``home_time`` seconds, open/close is immediate.
"""
from __future__ import annotations

import re

from . import gripper_protocol as P

_NUMBER = re.compile(rb"\s*([+-]?\d+)")
_BUFFER_SIZE = 256


class GripperFirmware:
    def __init__(self, speed: float = 4000.0, home_time: float = 0.3,
                 moving_report_period: float = 0.05, boot_time: float = 0.1):
        self.speed = float(speed)
        self.boot_time = boot_time
        self.home_time = home_time
        self.moving_report_period = moving_report_period
        self.status = "I"
        self.position = [0.0, 0.0, 0.0]
        self.target = [0.0, 0.0, 0.0]
        self.is_open = False
        self.message = ""
        self.toggle_steps = 240
        self.commands_seen: list[tuple[str, int]] = []
        self._buf = bytearray()
        self._now = 0.0
        self._homing_until: float | None = None
        self._next_report = 0.0
        self._booting_until: float | None = None

    # -- output helpers -------------------------------------------------------
    def status_line(self) -> bytes:
        if self.status == "E":
            return P.error_line(self.message)
        x, y, z = (int(round(v)) for v in self.position)
        return P.status_line(self.status, x, y, z, self.is_open)

    def _set_status(self, status: str, out: list[bytes]) -> None:
        if status != self.status:
            self.status = status
            out.append(self.status_line())
            self._next_report = self._now + self.moving_report_period

    # -- life cycle -----------------------------------------------------------
    def reset(self, now: float) -> bytes:
        """Power-up (the Arduino resets when the port opens): the sketch
        starts after ``boot_time`` (see :meth:`advance`)."""
        self._now = now
        self._buf.clear()
        self.status, self.message, self.is_open = "I", "", False
        self._homing_until = None
        self._booting_until = now + self.boot_time
        return self._boot() if self.boot_time <= 0 else b""

    @property
    def booting(self) -> bool:
        return self._booting_until is not None

    def _boot(self) -> bytes:
        self._booting_until = None
        out = [P.hello_line(), self.status_line()]
        self._home(out)
        return b"".join(out)

    def fail(self, message: str, now: float | None = None) -> bytes:
        """Enter the error state (e.g. an end stop problem)."""
        if now is not None:
            self._now = now
        self.message = message
        out: list[bytes] = []
        self._set_status("E", out)
        return b"".join(out)

    def _home(self, out: list[bytes], axes: str = "xyz") -> None:
        for i, name in enumerate("xyz"):
            if name in axes:
                self.target[i] = 0.0
        self._homing_until = self._now + self.home_time
        self._set_status("M", out)

    # -- time -----------------------------------------------------------------
    def advance(self, now: float) -> bytes:
        out: list[bytes] = []
        dt = max(0.0, now - self._now)
        self._now = now
        if self._booting_until is not None:
            return self._boot() if now >= self._booting_until else b""
        if self.status != "M":
            return b""
        step = self.speed * dt
        for i in range(3):
            d = self.target[i] - self.position[i]
            self.position[i] = self.target[i] if abs(d) <= step else self.position[i] + (step if d > 0 else -step)
        arrived = self.position == self.target
        if arrived and (self._homing_until is None or now >= self._homing_until):
            self._homing_until = None
            self._set_status("I", out)
        elif now >= self._next_report:
            self._next_report = now + self.moving_report_period
            out.append(self.status_line())
        return b"".join(out)

    # -- commands -------------------------------------------------------------
    def receive(self, data: bytes, now: float | None = None) -> bytes:
        out: list[bytes] = []
        if now is not None:
            out.append(self.advance(now))
        if self._booting_until is not None:
            return b"".join(out)             # the bootloader ignores the sketch's protocol
        for b in data:
            if b == ord(P.TERMINATOR):
                self._package(out)
                self._buf.clear()
                continue
            self._buf.append(b)
            if len(self._buf) >= _BUFFER_SIZE:
                self._buf.clear()
        return b"".join(out)

    def _package(self, out: list[bytes]) -> None:
        buf = bytes(self._buf)
        if len(buf) < 4:
            return
        start = buf.find(P.PREFIX.encode())
        if start < 0:
            return
        i = start + len(P.PREFIX)
        while i < len(buf):
            cmd = chr(buf[i])
            value = 0
            if cmd in P.COMMANDS:
                m = _NUMBER.match(buf, i + 1)
                if m is None:
                    return
                value = max(-2**31, min(2**31 - 1, int(m.group(1))))
                self.commands_seen.append((cmd, value))
                self._command(cmd, value, out)
            nxt = buf.find(b" ", i + 1)
            if nxt < 0:
                break
            i = nxt + 1

    def _command(self, cmd: str, value: int, out: list[bytes]) -> None:
        if cmd in "XYZ":
            if self.status != "E":
                self.target["XYZ".index(cmd)] = float(value)
                self._set_status("M", out)
        elif cmd == P.OPEN:
            self.is_open = True
        elif cmd == P.CLOSE:
            self.is_open = False
        elif cmd in (P.CALIBRATE, P.DOUBLE_CALIBRATE, P.CALIBRATE_X):
            if self.status != "E":
                self._home(out, "x" if cmd == P.CALIBRATE_X else "xyz")
        elif cmd == P.STOP:
            self._halt()
            if self.status != "E":
                self._set_status("I", out)
            out.append(self.status_line())
        elif cmd == P.FAST_STOP:
            self._halt()
        elif cmd == P.STATUS or cmd in "Txyzabmnopq":
            if cmd == P.TOGGLE_STEPS:
                self.toggle_steps = value
            out.append(self.status_line())

    def _halt(self) -> None:
        self.target = [float(round(v)) for v in self.position]
        self.position = list(self.target)
        self._homing_until = None
