"""Driver for the RCLL gripper's Arduino (text protocol, see
:mod:`gripper_protocol`), one I/O thread owning the port.

* On ``AT HELLO`` (the Arduino resets when its port opens) the driver sends
  the configuration again (accelerations m n o p, speeds x y z a, toggle
  steps T) and re-homes (``C0``).
* Every ``status_period`` (1 s) it asks ``AT S0 +``.
* A line with a wrong checksum is dropped and counted.
* An error status (``E``) is reported and the port is closed; it is
  reopened after ``reopen_interval`` (the Arduino resets, says HELLO and is
  configured and homed again).  No valid line for ``nodata_timeout`` does
  the same.

Positions cross the API in metres (gripper axes), the wire in steps.
"""
from __future__ import annotations

import logging
import math
import select
import threading
from collections.abc import Callable
from dataclasses import dataclass, field

from rll_bt.backend import BackendError, GripperState, GripperStatus
from rll_bt.clock import Clock, WallClock

from . import gripper_protocol as P
from .serial_port import LINK_ERRORS, open_serial, write_all

log = logging.getLogger(__name__)


@dataclass(frozen=True)
class GripperConfig:
    """Axis scale, firmware settings sent after HELLO (steps/s, steps/s^2
    for x, y, z, a), timing (s) and optional axis limits (m)."""
    steps: P.StepsPerMetre = field(default_factory=P.StepsPerMetre)
    speeds: tuple[int, int, int, int] = (4000, 4000, 4000, 7000)
    accels: tuple[int, int, int, int] = (7000, 7000, 7000, 15000)
    toggle_steps: int = 240
    status_period: float = 1.0
    nodata_timeout: float = 3.5
    reopen_interval: float = 1.0
    move_timeout: float = 20.0
    toggle_timeout: float = 3.0
    limits: tuple[float, float, float] | None = None

    def config_message(self) -> bytes:
        items = [(c, v) for c, v in zip("mnop", self.accels)]
        items += [(c, v) for c, v in zip("xyza", self.speeds)]
        items.append((P.TOGGLE_STEPS, self.toggle_steps))
        return P.encode_command(items)


@dataclass
class GripperLinkStats:
    lines: int = 0
    rejected: int = 0
    hellos: int = 0
    status_requests: int = 0
    errors: int = 0
    reopens: int = 0
    last_rejected: str = ""


class ArduinoGripper:
    """The gripper.  ``holding`` is a callable giving True/False/None
    (whether a workpiece is held, from a sensor); None means unknown."""

    def __init__(self, device: str, *, config: GripperConfig | None = None,
                 clock: Clock | None = None, holding: Callable[[], bool | None] | None = None):
        self.device = device
        self.config = config or GripperConfig()
        self.clock = clock or WallClock()
        self._holding = holding or (lambda: None)
        self._lock = threading.Lock()
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None
        self._port = None
        self._lines = P.LineSplitter()
        self._out: list[bytes] = []
        self.stats = GripperLinkStats()
        self._last: P.GripperMessage | None = None
        self._error = ""
        self._pending_home: tuple[float, bool] | None = None
        self._pending_move: tuple[tuple[int, int, int], float, bool] | None = None
        self._pending_open: tuple[bool, float] | None = None
        self._last_line = 0.0
        self._next_status = 0.0
        self._next_reopen = 0.0

    # -- life cycle ---------------------------------------------------------
    def open(self) -> ArduinoGripper:
        """Open the port (BackendUnavailable if impossible) and start the thread."""
        self._port = open_serial(self.device)
        self._on_opened(self.clock.now())
        self._stop.clear()
        self._thread = threading.Thread(target=self._run, name="robotino-gripper", daemon=True)
        self._thread.start()
        return self

    def close(self) -> None:
        self._stop.set()
        if self._thread is not None:
            self._thread.join(timeout=1.0)
            self._thread = None
        self._close_port()

    def _on_opened(self, now: float) -> None:
        self._lines.reset()
        self._last_line = now
        self._next_status = now + self.config.status_period

    def _close_port(self) -> None:
        port, self._port = self._port, None
        if port is not None:
            try:
                port.close()
            except LINK_ERRORS:
                pass

    # -- commands -------------------------------------------------------------
    def _send(self, message: bytes) -> None:
        with self._lock:
            if self._port is None:
                raise BackendError(f"gripper on {self.device} is not connected")
            self._out.append(message)

    def open_gripper(self) -> None:
        self._toggle(True)

    def close_gripper(self) -> None:
        self._toggle(False)

    def _toggle(self, want_open: bool) -> None:
        cmd = P.OPEN if want_open else P.CLOSE
        self._send(P.encode_command([(cmd, 0), (P.STATUS, 0)]))
        with self._lock:
            self._pending_open = (want_open, self.clock.now())

    def move(self, x: float, y: float, z: float) -> None:
        """Absolute axis target in metres."""
        try:
            steps = self.config.steps.to_steps(x, y, z)
        except ValueError as exc:
            raise BackendError(str(exc)) from None
        if self.config.limits is not None:
            for name, v, lim in zip("xyz", (x, y, z), self.config.limits):
                if v > lim:
                    raise BackendError(f"gripper {name} = {v:.4f} m beyond its limit {lim:.4f} m")
        self._send(P.encode_command(list(zip((P.MOVE_X, P.MOVE_Y, P.MOVE_Z), steps))))
        with self._lock:
            self._pending_move = (steps, self.clock.now(), False)

    def stop(self) -> None:
        self._send(P.encode_command([(P.STOP, 0)]))
        with self._lock:
            self._pending_move = None

    # -- status ---------------------------------------------------------------
    def status(self) -> GripperStatus:
        now = self.clock.now()
        with self._lock:
            last = self._last
            self._expire_pending(now)
            if self._error:
                state = GripperState.ERROR
            elif last is None or self._port is None:
                state = GripperState.UNKNOWN
            elif self._pending_move or self._pending_open or self._pending_home or last.state == "M":
                state = GripperState.MOVING
            else:
                state = GripperState.IDLE
            is_open = bool(last.is_open) if last is not None and last.is_open is not None else False
            position = (self.config.steps.to_metres(last.position) if last is not None
                        else (math.nan, math.nan, math.nan))
            message = self._error
        return GripperStatus(state, is_open, position, self._holding(), message)

    def _expire_pending(self, now: float) -> None:
        if self._pending_move and now - self._pending_move[1] > self.config.move_timeout:
            self._pending_move = None
            self._error = f"move not finished within {self.config.move_timeout:g} s"
        if self._pending_open and now - self._pending_open[1] > self.config.toggle_timeout:
            self._pending_open = None
        if self._pending_home and now - self._pending_home[0] > self.config.move_timeout:
            self._pending_home = None
            self._error = f"homing not finished within {self.config.move_timeout:g} s"

    # -- the I/O thread -------------------------------------------------------------
    def _run(self) -> None:
        while not self._stop.is_set():
            now = self.clock.now()
            if self._port is None:
                if now >= self._next_reopen:
                    self._reopen(now)
                else:
                    self._stop.wait(min(0.05, self._next_reopen - now))
                continue
            self._flush_out(now)
            port = self._port
            if port is None:
                continue
            try:
                ready, _, _ = select.select([port.fileno()], [], [], 0.02)
                data = port.read(4096) if ready else b""
            except LINK_ERRORS as exc:
                self._lose(f"read failed ({exc})")
                continue
            now = self.clock.now()
            for line in self._lines.feed(data):
                self._on_line(line, now)
            if self._port is not None and now - self._last_line > self.config.nodata_timeout:
                self._lose(f"no valid line for {now - self._last_line:.1f} s")

    def _flush_out(self, now: float) -> None:
        with self._lock:
            if now >= self._next_status:
                self._next_status = now + self.config.status_period
                self._out.append(P.encode_command([(P.STATUS, 0)]))
                self.stats.status_requests += 1
            out, self._out = self._out, []
        for message in out:
            try:
                write_all(self._port, message)
            except LINK_ERRORS as exc:
                self._lose(f"write failed ({exc})")
                return

    def _reopen(self, now: float) -> None:
        self._next_reopen = now + self.config.reopen_interval
        try:
            self._port = open_serial(self.device)
        except BackendError as exc:
            log.debug("gripper reopen failed: %s", exc)
            return
        self.stats.reopens += 1
        self._on_opened(now)

    def _lose(self, why: str) -> None:
        log.warning("gripper %s: %s; closing and reopening", self.device, why)
        self._close_port()
        self._next_reopen = self.clock.now() + self.config.reopen_interval
        with self._lock:
            self._out.clear()

    def _on_line(self, line: bytes, now: float) -> None:
        msg = P.parse_line(line)
        if isinstance(msg, P.Rejected):
            self.stats.rejected += 1
            self.stats.last_rejected = msg.reason
            log.debug("gripper line rejected (%s): %r", msg.reason, msg.line)
            return
        self.stats.lines += 1
        self._last_line = now
        if msg.kind == "hello":
            self.stats.hellos += 1
            with self._lock:
                self._error = ""
                self._pending_home = (now, False)
                self._pending_move = None
                self._out += [self.config.config_message(), P.encode_command([(P.CALIBRATE, 0)])]
            return
        with self._lock:
            if msg.state == "E":
                self.stats.errors += 1
                self._error = msg.text or "gripper reports an error"
                self._pending_move = self._pending_open = self._pending_home = None
            self._last = msg
            self._update_pending(msg)
        if msg.state == "E":
            self._lose(f"gripper error: {msg.text}")

    def _update_pending(self, msg: P.GripperMessage) -> None:
        if msg.state == "M":
            if self._pending_move:
                target, t, _ = self._pending_move
                self._pending_move = (target, t, True)
            if self._pending_home:
                self._pending_home = (self._pending_home[0], True)
        elif msg.state == "I":
            if self._pending_home and self._pending_home[1]:
                self._pending_home = None
            if self._pending_move:
                target, _, seen_moving = self._pending_move
                if seen_moving or tuple(msg.position) == tuple(target):
                    self._pending_move = None
        if self._pending_open and msg.is_open is not None and msg.is_open == self._pending_open[0]:
            self._pending_open = None
