"""The Robotino 3 base driver: one I/O thread owning the serial port.

Every ``cycle_time`` (default 5 ms) the thread sends one frame holding the
GET tags Fawkes polls and, while the robot should move (and until the
wheels have stopped), the three SET_MOTOR_SPEED set-points of the ramped
body velocity, so the base's communication watchdog never fires while
driving.  Replies are decoded as they stream in; odometry is integrated
from the measured wheel speeds of each ALL_MOTOR_READINGS.

Fault handling (Fawkes semantics):

* read timeout: a frame not finished ``read_timeout`` after its head ->
  input cleared, GET_HW_VERSION ping, polling goes on;
* no-data timeout: no valid frame for ``nodata_timeout`` -> port closed and
  reopened (every ``reopen_interval``) until it works; driving resumes;
* checksum or framing error: input cleared, counted; after
  ``recover_bound`` in a row a ping and an immediate re-request;
* read or write error (device gone): port closed and reopened;
* host deadman: a non-zero command older than ``deadman`` s is replaced by
  zero (the ramp then brings the robot to rest).

Times come from ``clock`` (monotonic seconds; WallClock by default).
"""
from __future__ import annotations

import logging
import math
import select
import threading
from collections import deque
from dataclasses import dataclass, replace

from rll_bt.backend import BackendUnavailable
from rll_bt.clock import Clock, WallClock

from . import tags as T
from .framing import ChecksumMismatch, Frame, FrameDecoder, encode_frame
from .kinematics import OdometryIntegrator, OmniKinematics
from .ramp import RampLimits, ramp
from .serial_port import LINK_ERRORS, find_device, open_serial, write_all

log = logging.getLogger(__name__)

#: what one poll asks for (Fawkes' request, in Fawkes' order)
POLL_TAGS = (T.GetAllMotorReadings(), T.GetDistanceSensorReadings(), T.GetAllAnalogInputs(),
             T.GetAllDigitalInputs(), T.GetBumper(), T.GetOdometry(), T.GetGyroZAngle())
VERSION_REQUEST = (T.GetHwVersion(), T.GetSwVersion())
RX_MAX_PAYLOAD = 4096          # the base's replies may exceed its own 512-byte rx limit


@dataclass(frozen=True)
class BaseReadings:
    """The latest values the base reported.  ``stamp`` is the clock time of
    the reply; speeds rpm, positions ticks, currents A, voltages V."""
    stamp: float = math.nan
    motor_speeds: tuple = (0, 0, 0, 0)
    motor_positions: tuple = (0, 0, 0, 0)
    motor_currents: tuple = (0.0, 0.0, 0.0, 0.0)
    distance_voltages: tuple = (0.0,) * 9
    analog_inputs: tuple = (0.0,) * 8
    digital_inputs: int = 0
    bumper: bool = False
    power_button: bool = False
    firmware_odometry: tuple = (0.0, 0.0, 0.0)
    gyro: tuple | None = None
    power: T.PowerSourceReadings | None = None
    charger_info: tuple = ()
    charger_error: T.ChargerError | None = None


@dataclass
class LinkStats:
    """Counters of the serial link (all only grow)."""
    polls: int = 0
    frames: int = 0
    checksum_errors: int = 0
    framing_errors: int = 0
    read_timeouts: int = 0
    nodata_timeouts: int = 0
    link_losses: int = 0
    reopens: int = 0
    write_errors: int = 0
    recoveries: int = 0
    base_errors: int = 0
    last_base_error: str = ""
    deadman_stops: int = 0


class RobotinoBase:
    """Driver for the base.  :meth:`open` connects and starts the thread."""

    def __init__(self, device: str | None = None, *, clock: Clock | None = None,
                 kinematics: OmniKinematics | None = None, ramp_limits: RampLimits | None = None,
                 cycle_time: float = 0.005, read_timeout: float = 0.2, nodata_timeout: float = 2.0,
                 deadman: float = 0.5, recover_bound: int = 2, emergency_bumper: bool = True,
                 handshake_timeout: float = 1.0, reopen_interval: float = 0.05,
                 zero_repeat: int = 10, history: int = 200_000):
        if not 0.005 <= cycle_time <= 0.010:
            raise ValueError(f"cycle_time must be 5 to 10 ms, got {cycle_time * 1000:g} ms")
        for name, value in (("read_timeout", read_timeout), ("nodata_timeout", nodata_timeout),
                            ("deadman", deadman), ("handshake_timeout", handshake_timeout)):
            if not value > 0:
                raise ValueError(f"{name} must be > 0, got {value}")
        self.device = device
        self.clock = clock or WallClock()
        self.kinematics = kinematics or OmniKinematics()
        self.ramp_limits = ramp_limits or RampLimits()
        self.cycle_time = cycle_time
        self.read_timeout = read_timeout
        self.nodata_timeout = nodata_timeout
        self.deadman = deadman
        self.recover_bound = max(1, recover_bound)
        self.emergency_bumper = emergency_bumper
        self.handshake_timeout = handshake_timeout
        self.reopen_interval = reopen_interval
        self.zero_repeat = zero_repeat
        self.versions: tuple[str, str] = ("", "")

        self._lock = threading.Lock()
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None
        self._port = None
        self._decoder = FrameDecoder(RX_MAX_PAYLOAD)
        self._stats = LinkStats()
        self._readings = BaseReadings()
        self._odo = OdometryIntegrator(self.kinematics)
        self._odo_stamp = math.nan
        self._last_reading_time: float | None = None
        self._target = (0.0, 0.0, 0.0)
        self._target_time = -math.inf
        self._ramped = (0.0, 0.0, 0.0)
        self._zero_left = 0
        self._extra: list[T.Tag] = []
        self._last_cycle: float | None = None
        self._last_frame = 0.0
        self._frame_started: float | None = None
        self._consecutive_errors = 0
        self._next_reopen = 0.0
        self._periods: deque = deque(maxlen=history)

    # -- life cycle ---------------------------------------------------------
    def open(self) -> RobotinoBase:
        """Open the port, do the Fawkes handshake, start polling.
        Raises :class:`BackendUnavailable` when the base does not answer."""
        if self.device is None:
            self.device = find_device()
        self._port = open_serial(self.device)
        self._stop.clear()
        try:
            self._handshake()
        except BaseException:
            self._close_port()
            raise
        self._thread = threading.Thread(target=self._run, name="robotino-base", daemon=True)
        self._thread.start()
        self._wait_for_readings()
        return self

    def _wait_for_readings(self) -> None:
        """Until the first poll is answered (odometry stamped, power read), at most
        ``handshake_timeout``: readings are real from the moment :meth:`open` returns."""
        for _ in range(int(self.handshake_timeout / self.cycle_time) + 1):
            with self._lock:
                if not math.isnan(self._odo_stamp) and self._readings.power is not None:
                    return
            self._stop.wait(self.cycle_time)

    def close(self) -> None:
        """Stop the wheels (best effort), end the thread, release the port."""
        if self._thread is not None:
            self.stop_now()
            deadline = self.clock.now() + 0.3
            while self.clock.now() < deadline and self._thread.is_alive():
                with self._lock:
                    settled = not any(self._readings.motor_speeds[:3]) and self._zero_left == 0
                if settled:
                    break
                self._stop.wait(self.cycle_time)
            self._stop.set()
            self._thread.join(timeout=1.0)
            self._thread = None
        self._close_port()

    @property
    def connected(self) -> bool:
        return self._port is not None

    def _handshake(self) -> None:
        deadline = self.clock.now() + self.handshake_timeout
        hw = sw = ""
        while not (hw and sw):
            if self.clock.now() >= deadline:
                raise BackendUnavailable(
                    f"no reply to the version inquiry from {self.device} within "
                    f"{self.handshake_timeout:g} s (is it a Robotino base? is controld3 running?)")
            if self._port is None:          # lost during the handshake: the device may come back
                try:
                    self._port = open_serial(self.device)
                except BackendUnavailable:
                    self._stop.wait(self.reopen_interval)
                    continue
            self._write(VERSION_REQUEST)
            resend = self.clock.now() + 0.25
            while not (hw and sw) and self.clock.now() < min(resend, deadline):
                for tag in self._read_tags(0.02):
                    if isinstance(tag, T.HwVersion):
                        hw = tag.text
                    elif isinstance(tag, T.SwVersion):
                        sw = tag.text
        self.versions = (hw, sw)
        log.info("Robotino base on %s: hardware %s, firmware %s", self.device, hw, sw)
        self._odo.reset()
        for tags in ((T.SetAllDigitalOutputs(0),), (T.SetOdometry(0.0, 0.0, 0.0),),
                     (T.SetEmergencyBumper(int(self.emergency_bumper)),)):
            self._write(tags)
        self._last_frame = self.clock.now()

    def _read_tags(self, timeout: float) -> list[T.Tag]:
        out: list[T.Tag] = []
        for event in self._decoder.feed(self._read_raw(timeout)):
            if isinstance(event, Frame):
                out.extend(T.decode_tags(event.payload))
        return out

    # -- commands from other threads ------------------------------------------
    def set_velocity(self, vx: float, vy: float, omega: float) -> None:
        """Desired body velocity (m/s, m/s, rad/s); refreshes the deadman."""
        values = (float(vx), float(vy), float(omega))
        if not all(math.isfinite(v) for v in values):
            raise ValueError(f"velocity must be finite, got {values}")
        with self._lock:
            self._target = values
            self._target_time = self.clock.now()

    def stop_now(self) -> None:
        """Zero the command and the ramp: the next frame sends zero set-points."""
        with self._lock:
            self._target = (0.0, 0.0, 0.0)
            self._ramped = (0.0, 0.0, 0.0)
            self._zero_left = max(self._zero_left, self.zero_repeat)

    def send_tags(self, *tags: T.Tag) -> None:
        """Add tags (e.g. SetAllDigitalOutputs) to the next poll frame."""
        with self._lock:
            self._extra.extend(tags)

    # -- readings ---------------------------------------------------------------
    def readings(self) -> BaseReadings:
        with self._lock:
            return self._readings

    def odometry(self) -> tuple[float, float, float, float, float, float, float]:
        """(stamp, x, y, phi, vx, vy, omega) of the integrated odometry."""
        with self._lock:
            o = self._odo
            return (self._odo_stamp, o.x, o.y, o.phi, o.vx, o.vy, o.omega)

    def reset_odometry(self, x: float = 0.0, y: float = 0.0, phi: float = 0.0) -> None:
        with self._lock:
            self._odo.reset(x, y, phi)

    def stats(self) -> LinkStats:
        with self._lock:
            return replace(self._stats)

    def cycle_periods(self) -> list[float]:
        """Seconds between consecutive poll frames (for benchmarks)."""
        with self._lock:
            return list(self._periods)

    # -- the I/O thread -----------------------------------------------------------
    def _run(self) -> None:
        next_poll = self.clock.now()
        while not self._stop.is_set():
            now = self.clock.now()
            if self._port is None:
                self._try_reopen(now)
                next_poll = self.clock.now()
                continue
            if now >= next_poll:
                self._cycle(now)
                next_poll += self.cycle_time
                if next_poll < now:
                    next_poll = now + self.cycle_time
            self._receive(max(0.0, next_poll - self.clock.now()))
            self._check_timeouts(self.clock.now())

    def _try_reopen(self, now: float) -> None:
        if now < self._next_reopen:
            self._stop.wait(min(self.reopen_interval, self._next_reopen - now))
            return
        self._next_reopen = now + self.reopen_interval
        try:
            self._port = open_serial(self.device)
        except BackendUnavailable as exc:
            log.debug("reopen failed: %s", exc)
            return
        with self._lock:
            self._stats.reopens += 1
        log.warning("Robotino base %s reopened", self.device)
        self._decoder.reset()
        self._frame_started = None
        self._last_frame = self.clock.now()
        self._last_cycle = None
        self._write(VERSION_REQUEST)
        self._write((T.SetEmergencyBumper(int(self.emergency_bumper)),))   # in case the base rebooted

    def _lose_link(self, why: str) -> None:
        log.warning("Robotino base %s: %s; closing and reopening", self.device, why)
        with self._lock:
            self._stats.link_losses += 1
        self._close_port()
        self._next_reopen = self.clock.now() + self.reopen_interval

    def _close_port(self) -> None:
        port, self._port = self._port, None
        if port is not None:
            try:
                port.close()
            except LINK_ERRORS:
                pass
        self._decoder.reset()
        self._frame_started = None

    def _cycle(self, now: float) -> None:
        with self._lock:
            if any(self._target) and now - self._target_time >= self.deadman:
                self._target = (0.0, 0.0, 0.0)
                self._stats.deadman_stops += 1
                log.info("deadman: no drive command for %.2f s, stopping", now - self._target_time)
            dt = self.cycle_time if self._last_cycle is None else min(0.1, now - self._last_cycle)
            if self._last_cycle is not None:
                self._periods.append(now - self._last_cycle)
            self._last_cycle = now
            self._ramped = ramp(self._ramped, self._target, dt, self.ramp_limits)
            moving = any(self._ramped) or any(self._target)
            if moving:
                self._zero_left = self.zero_repeat
            wheels_turning = any(self._readings.motor_speeds[:3])
            tags: list[T.Tag] = []
            if moving or self._zero_left > 0 or wheels_turning:
                sp = self.kinematics.setpoints(*self._ramped)
                tags.extend(T.SetMotorSpeed(i, sp[i]) for i in range(3))
                if not moving and self._zero_left > 0:
                    self._zero_left -= 1
            tags.extend(self._extra)
            self._extra.clear()
            self._stats.polls += 1
        tags.extend(POLL_TAGS)
        self._write(tags)

    def _write(self, tags) -> None:
        port = self._port
        if port is None:
            return
        try:
            write_all(port, encode_frame(T.encode_tags(tags)))
        except LINK_ERRORS as exc:
            with self._lock:
                self._stats.write_errors += 1
            self._lose_link(f"write failed ({exc})")

    def _read_raw(self, timeout: float) -> bytes:
        port = self._port
        if port is None:
            return b""
        try:
            ready, _, _ = select.select([port.fileno()], [], [], timeout)
            return port.read(4096) if ready else b""
        except LINK_ERRORS as exc:
            self._lose_link(f"read failed ({exc})")
            return b""

    def _receive(self, timeout: float) -> None:
        data = self._read_raw(timeout)
        if not data:
            return
        now = self.clock.now()
        ended = self._decoder.frames + self._decoder.checksum_errors + self._decoder.oversize
        events = self._decoder.feed(data)
        for event in events:
            if isinstance(event, Frame):
                self._on_frame(event.payload, now)
            else:
                self._on_bad_frame(event, now)
                if self._port is None:
                    return
        if not self._decoder.in_frame:
            self._frame_started = None
        elif self._frame_started is None or (
                self._decoder.frames + self._decoder.checksum_errors + self._decoder.oversize != ended):
            self._frame_started = now

    def _on_bad_frame(self, event, now: float) -> None:
        with self._lock:
            if isinstance(event, ChecksumMismatch):
                self._stats.checksum_errors += 1
            else:
                self._stats.framing_errors += 1
        self._consecutive_errors += 1
        self._clear_input()
        if self._consecutive_errors >= self.recover_bound:
            self._consecutive_errors = 0
            with self._lock:
                self._stats.recoveries += 1
            self._write((T.GetHwVersion(),))
            self._write(POLL_TAGS)

    def _clear_input(self) -> None:
        self._decoder.reset()
        self._frame_started = None
        if self._port is not None:
            try:
                self._port.reset_input_buffer()
            except LINK_ERRORS as exc:
                self._lose_link(f"flush failed ({exc})")

    def _check_timeouts(self, now: float) -> None:
        if self._port is None:
            return
        if self._frame_started is not None and now - self._frame_started > self.read_timeout:
            with self._lock:
                self._stats.read_timeouts += 1
            log.warning("read timeout: frame unfinished after %.0f ms; pinging", self.read_timeout * 1e3)
            self._clear_input()
            self._write((T.GetHwVersion(),))
        if now - self._last_frame > self.nodata_timeout:
            with self._lock:
                self._stats.nodata_timeouts += 1
            self._lose_link(f"no data for {now - self._last_frame:.1f} s")

    def _on_frame(self, payload: bytes, now: float) -> None:
        self._last_frame = now
        self._consecutive_errors = 0
        tags = T.decode_tags(payload)
        with self._lock:
            self._stats.frames += 1
            r = self._readings
            updates: dict = {"stamp": now}
            for tag in tags:
                if isinstance(tag, T.AllMotorReadings):
                    updates.update(motor_speeds=tag.speeds, motor_positions=tag.positions,
                                   motor_currents=tag.currents)
                    self._integrate(tag.speeds, now)
                elif isinstance(tag, T.DistanceSensorReadings):
                    updates["distance_voltages"] = tag.values
                elif isinstance(tag, T.AllAnalogInputs):
                    updates["analog_inputs"] = tag.values
                elif isinstance(tag, T.AllDigitalInputs):
                    updates["digital_inputs"] = tag.value
                elif isinstance(tag, T.Bumper):
                    updates["bumper"] = bool(tag.value)
                elif isinstance(tag, T.PowerButton):
                    updates["power_button"] = bool(tag.value)
                elif isinstance(tag, T.Odometry):
                    updates["firmware_odometry"] = (tag.x, tag.y, tag.phi)
                elif isinstance(tag, T.GyroZAngle):
                    updates["gyro"] = (tag.angle, tag.rate)
                elif isinstance(tag, T.PowerSourceReadings):
                    updates["power"] = tag
                elif isinstance(tag, T.ChargerInfo):
                    others = tuple(c for c in r.charger_info if c.charger != tag.charger)
                    updates["charger_info"] = tuple(sorted(others + (tag,), key=lambda c: c.charger))
                elif isinstance(tag, T.ChargerError):
                    updates["charger_error"] = tag
                    log.warning("charger %d error: %s", tag.charger, tag.text)
                elif isinstance(tag, T.Error):
                    self._stats.base_errors += 1
                    self._stats.last_base_error = tag.text
                    log.debug("base error: %s", tag.text)
                elif isinstance(tag, T.HwVersion):
                    self.versions = (tag.text, self.versions[1])
                elif isinstance(tag, T.SwVersion):
                    self.versions = (self.versions[0], tag.text)
            self._readings = replace(r, **updates)

    def _integrate(self, speeds: tuple, now: float) -> None:
        dt = 0.0 if self._last_reading_time is None else now - self._last_reading_time
        if dt > 1.0:             # after a gap, do not extrapolate over it
            dt = 0.0
        self._last_reading_time = now
        self._odo.update(tuple(float(s) for s in speeds[:3]), dt)
        self._odo_stamp = now
