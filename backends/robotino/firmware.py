"""A model of the Robotino 3 base firmware (robot side of the serial link).

Pure logic, no I/O: :meth:`BaseFirmware.receive` takes bytes from the host,
:meth:`BaseFirmware.take_reply` gives the one reply frame the main loop would
send (or None), :meth:`BaseFirmware.advance` runs the 1 kHz motor loop and the
100 ms communication watchdog up to a time (seconds).  Behaviour follows the
base firmware (1.2.3 parser texts):

* request/response only: a reply only when parsing produced a tag, and then
  always with POWER_SOURCE_READINGS (65) and POWER_BUTTON (39) appended;
* ERROR tags: ``RX checksum mismatch <in> <out>`` (hex), ``payload to long:
  <L> > 512``, ``Tag <n> not implemented``, ``<TAG> invalid length <n>``;
* watchdog: a 100 ms tick; when more than 3 ticks have passed since the last
  valid frame (so 300-400 ms after it, as the fact sheet states; the
  firmware's own counter notices a frame only at the next tick, which can add
  up to one tick) all motors stop until a new SET_MOTOR_SPEED;
* motors: set-point ramped within the accel limits (default +-12 rpm/ms),
  ideal speed tracking, 2000 ticks per motor revolution, measured speed
  30 x ticks-per-ms (30 rpm resolution);
* ground truth: the wheels' actual speeds integrated into a world pose
  (x, y in m, theta in rad) with the omni-drive kinematics.
"""
from __future__ import annotations

import math
from collections import deque

from . import tags as T
from .firmware_handlers import HANDLERS, int32
from .framing import MAX_PAYLOAD, ChecksumMismatch, FrameDecoder, Oversize, encode_frame, stuff
from .kinematics import OmniKinematics

TICKS_PER_REV = 2000
RPM_PER_TICK_PER_MS = 60000 // TICKS_PER_REV        # 30 rpm resolution
PRODUCER_PAYLOAD_SIZE = 1024 - 5 - 4               # escaped bytes the tx buffer holds
WATCHDOG_TICK_MS = 100
WATCHDOG_MAX_INACTIVE = 3


class Motor:
    """One motor channel.  Speeds in rpm, accel limits in rpm/ms, position in ticks."""

    def __init__(self) -> None:
        self.setpoint = 0
        self.ss = 0.0            # ramped set-point = actual speed in this model
        self.position = 0.0
        self.measured = 0
        self.min_accel = -12.0
        self.max_accel = 12.0
        self.kp, self.ki = 0.1, 0.005
        self.on = True

    def stop(self) -> None:
        self.setpoint = 0
        self.ss = 0.0

    def step(self, setpoint: float) -> None:
        """One millisecond of the PI loop with accel limiting."""
        d = min(max(setpoint - self.ss, self.min_accel), self.max_accel)
        self.ss += d
        if -1.0 < self.ss < 1.0:
            self.ss = 0.0
        self.advance(1)

    def advance(self, ms: int) -> None:
        """``ms`` milliseconds at the current speed."""
        before = math.floor(self.position + self.ss / RPM_PER_TICK_PER_MS * (ms - 1))
        self.position += self.ss / RPM_PER_TICK_PER_MS * ms
        self.measured = RPM_PER_TICK_PER_MS * (math.floor(self.position) - before)

    @property
    def settled(self) -> bool:
        return self.ss == self.setpoint

    @property
    def current(self) -> float:
        """A synthetic motor current (A)."""
        return 0.05 + 0.0004 * abs(self.ss) if self.on else 0.0


class BaseFirmware:
    """The base's state and protocol behaviour.  Times are seconds."""

    def __init__(self, kinematics: OmniKinematics | None = None, *, hw_version: str = "3.0.0",
                 sw_version: str = "1.2.3", start: float = 0.0, num_chargers: int = 2,
                 charger_info_period: float = 1.0, log_size: int = 200_000):
        self.kinematics = kinematics or OmniKinematics()
        self.hw_version, self.sw_version = hw_version, sw_version
        self.motors = [Motor() for _ in range(4)]
        self.decoder = FrameDecoder(MAX_PAYLOAD)
        self.t_ms = int(round(start * 1000))
        # inputs a test or the CLI may set
        self.distance = [0.3] * 9
        self.analog = [0.0] * 8
        self.digital_inputs = 0
        self.bumper = False
        self.power_button = False
        self.safety_pin_low = False
        self.battery_voltage = 24.5
        self.ext_power = False
        self.num_chargers = num_chargers
        # outputs and settings the host may change
        self.digital_outputs = 0
        self.relays = 0
        self.emergency_bumper = False
        self.odometry = (0.0, 0.0, 0.0)
        self.safety_velocity = 400.0
        self.battery_min = (19.0, 19.8)
        self.gyro_param = (0.0, 1.0)
        self.fpga_power, self.pwr_ok, self.nrst, self.boot = 1, 1, 1, 0
        self.powered_off = False
        self.config_reset_pending = False
        self.can_tx: list[tuple[int, int, bytes]] = []
        # ground truth (world frame) and observers' logs
        self.pose = [0.0, 0.0, 0.0]
        self.twist = (0.0, 0.0, 0.0)
        self.setpoint_log: deque = deque(maxlen=log_size)
        self.rx_log: deque = deque(maxlen=log_size)        # (time, payload) of valid frames
        self.errors_sent: deque = deque(maxlen=1000)
        # watchdog
        self.rx_counter = 0
        self._ticks_since_frame = WATCHDOG_MAX_INACTIVE
        self.com_active = False
        self.watchdog_trips = 0            # active -> inactive transitions
        self.watchdog_motion_stops = 0     # ... of which stopped turning motors
        self.watchdog_trip_times: list[float] = []
        # chargers
        self._charger_period_ms = int(charger_info_period * 1000)
        self._next_charger_info = self.t_ms + self._charger_period_ms
        self._charger_info_due: set[int] = set()
        self._charger_version_due: set[int] = set()
        # reply being produced
        self._produced: list[bytes] = []
        self._produced_escaped = 0
        self.replies = 0

    # -- time ---------------------------------------------------------------
    @property
    def now(self) -> float:
        return self.t_ms / 1000.0

    def _setpoint(self, i: int) -> float:
        m = self.motors[i]
        if not self.safety_pin_low or i > 2:
            return m.setpoint
        if not self.digital_inputs & 0x1:
            return 0
        if not self.digital_inputs & 0x2:
            peak = max(abs(self.motors[j].setpoint) for j in range(3))
            if peak > self.safety_velocity:
                return m.setpoint * self.safety_velocity / peak
        return m.setpoint

    def advance(self, now: float) -> None:
        """Run the motor loop (1 ms steps) and the watchdog up to ``now``."""
        target = int(now * 1000)
        while self.t_ms < target:
            if self.emergency_bumper and self.bumper:
                self.stop_all()
            to_tick = WATCHDOG_TICK_MS - self.t_ms % WATCHDOG_TICK_MS
            span = min(target - self.t_ms, to_tick)
            if all(m.settled for m in self.motors) and not self.safety_pin_low:
                for m in self.motors:
                    m.advance(span)
                self._integrate_pose(span)
                self.t_ms += span
            else:
                for i, m in enumerate(self.motors):
                    m.step(self._setpoint(i))
                self._integrate_pose(1)
                self.t_ms += 1
            if self.t_ms % WATCHDOG_TICK_MS == 0:
                self._watchdog_tick()
            if self.t_ms >= self._next_charger_info:
                self._next_charger_info += self._charger_period_ms
                self._charger_info_due.update(range(self.num_chargers))

    def _integrate_pose(self, ms: int) -> None:
        vx, vy, w = self.kinematics.inverse(*(m.ss for m in self.motors[:3]))
        self.twist = (vx, vy, w)
        dt = ms / 1000.0
        x, y, th = self.pose
        if abs(w) < 1e-12:
            dx, dy = vx * dt, vy * dt
        else:
            s, c = math.sin(w * dt), math.cos(w * dt)
            dx = (s * vx - (1.0 - c) * vy) / w
            dy = ((1.0 - c) * vx + s * vy) / w
        ct, st = math.cos(th), math.sin(th)
        self.pose = [x + ct * dx - st * dy, y + st * dx + ct * dy, th + w * dt]

    def _watchdog_tick(self) -> None:
        self._ticks_since_frame += 1
        if self._ticks_since_frame > WATCHDOG_MAX_INACTIVE:
            if self.com_active:
                self.watchdog_trips += 1
                self.watchdog_trip_times.append(self.now)
                if any(m.setpoint or m.ss for m in self.motors):
                    self.watchdog_motion_stops += 1
            self.com_active = False
            self.stop_all()
        else:
            self.com_active = True

    def stop_all(self) -> None:
        for m in self.motors:
            m.stop()

    def skip(self, now: float) -> None:
        """The time up to ``now`` passes with the motors stopped and no loop run:
        what an emulator that was not scheduled makes of a microcontroller (the
        wheels stand, the encoders do not move, the watchdog's count goes on
        from where it was: a host that is really silent still trips it)."""
        self.stop_all()
        for m in self.motors:
            m.measured = 0
        self.twist = (0.0, 0.0, 0.0)
        target = int(now * 1000)
        if target <= self.t_ms:
            return
        self.t_ms = target
        while self._next_charger_info <= self.t_ms:
            self._next_charger_info += self._charger_period_ms
            self._charger_info_due.update(range(self.num_chargers))

    # -- receiving ----------------------------------------------------------
    def receive(self, data: bytes, now: float | None = None) -> None:
        """Bytes from the host (escaped, as on the wire)."""
        if now is not None:
            self.advance(now)
        if self.powered_off:
            return
        for event in self.decoder.feed(data):
            if isinstance(event, ChecksumMismatch):
                self.report_error(f"RX checksum mismatch {event.received:x} {event.computed:x}")
            elif isinstance(event, Oversize):
                self.report_error(f"payload to long: {event.length} > {MAX_PAYLOAD}\n\r")
            else:
                self.rx_counter += 1
                self.rx_log.append((self.now, event.payload))
                self._ticks_since_frame = 0
                self.com_active = True
                self._parse(event.payload)

    def _parse(self, payload: bytes) -> None:
        i, length = 0, len(payload)
        while length >= 2:
            tag_id, tag_len = payload[i], payload[i + 1]
            if tag_len > length - 2:
                self.report_error(f"tag_length={tag_len} greater than length={length}")
                return
            self._dispatch(tag_id, bytes(payload[i + 2:i + 2 + tag_len]))
            i += tag_len + 2
            length -= tag_len + 2

    def _dispatch(self, tag_id: int, data: bytes) -> None:
        handler = HANDLERS.get(tag_id)
        if handler is None:
            self.report_error(f"Tag {tag_id} not implemented")
            return
        name, size, fn = handler
        if size is not None and len(data) != size:
            self.report_error(f"{name} invalid length {len(data)}")
            return
        fn(self, data)

    # -- producing ----------------------------------------------------------
    def produce(self, tag: T.Tag) -> None:
        """Add a tag to the reply being produced (an overrun replaces it by an ERROR)."""
        tlv = tag.encode()
        if self._produced_escaped + 2 * len(tlv) > PRODUCER_PAYLOAD_SIZE:
            self._produced.clear()
            self._produced_escaped = 0
            self.produce(T.Error("producer_buffer overrun"))
            return
        self._produced.append(tlv)
        self._produced_escaped += len(stuff(tlv))

    def report_error(self, text: str) -> None:
        """An ERROR tag with ``text`` (at most 127 characters) in the reply."""
        text = text[:127]
        self.errors_sent.append(text)
        self.produce(T.Error(text))

    def take_reply(self) -> bytes | None:
        """The frame the main loop sends now, or None when nothing was produced."""
        if not self._produced or self.powered_off:
            self._produced.clear()
            return None
        if self.config_reset_pending:
            self.config_reset_pending = False
            self.produce(T.ConfigReset(1))
        for c in sorted(self._charger_info_due):
            self.produce(self._charger_info(c))
        for c in sorted(self._charger_version_due):
            self.produce(T.ChargerVersion(c, 1, 2, 3))
        self._charger_info_due.clear()
        self._charger_version_due.clear()
        self.produce(self.power_source_readings())
        self.produce(T.PowerButton(int(self.power_button)))
        payload = b"".join(self._produced)
        self._produced.clear()
        self._produced_escaped = 0
        self.replies += 1
        return encode_frame(payload)

    def power_source_readings(self) -> T.PowerSourceReadings:
        current = 1.0 + sum(m.current for m in self.motors)
        low = int(not self.ext_power and 5.0 < self.battery_voltage < self.battery_min[0])
        return T.PowerSourceReadings(self.battery_voltage, current, int(self.ext_power),
                                     self.num_chargers, 1 if self.num_chargers > 1 else 0,
                                     low, 60000)

    def _charger_info(self, c: int) -> T.ChargerInfo:
        return T.ChargerInfo(c, self.t_ms // 1000, self.battery_voltage, -0.5, 25.0, 25.0, 0,
                             "Discharging")

    def motor_readings(self) -> T.AllMotorReadings:
        return T.AllMotorReadings(tuple(m.measured for m in self.motors),
                                  tuple(int32(m.position) for m in self.motors),
                                  tuple(m.current for m in self.motors))

    @property
    def fw_major(self) -> int:
        try:
            return int(self.sw_version.split(".")[0])
        except ValueError:
            return 1
