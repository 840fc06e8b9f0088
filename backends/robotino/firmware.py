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
import struct
from collections import deque

from . import tags as T
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

    # -- receiving ----------------------------------------------------------
    def receive(self, data: bytes, now: float | None = None) -> None:
        """Bytes from the host (escaped, as on the wire)."""
        if now is not None:
            self.advance(now)
        if self.powered_off:
            return
        for event in self.decoder.feed(data):
            if isinstance(event, ChecksumMismatch):
                self._error(f"RX checksum mismatch {event.received:x} {event.computed:x}")
            elif isinstance(event, Oversize):
                self._error(f"payload to long: {event.length} > {MAX_PAYLOAD}\n\r")
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
                self._error(f"tag_length={tag_len} greater than length={length}")
                return
            self._dispatch(tag_id, bytes(payload[i + 2:i + 2 + tag_len]))
            i += tag_len + 2
            length -= tag_len + 2

    def _dispatch(self, tag_id: int, data: bytes) -> None:
        handler = _HANDLERS.get(tag_id)
        if handler is None:
            self._error(f"Tag {tag_id} not implemented")
            return
        name, size, fn = handler
        if size is not None and len(data) != size:
            self._error(f"{name} invalid length {len(data)}")
            return
        fn(self, data)

    # -- producing ----------------------------------------------------------
    def _produce(self, tag: T.Tag) -> None:
        tlv = tag.encode()
        if self._produced_escaped + 2 * len(tlv) > PRODUCER_PAYLOAD_SIZE:
            self._produced.clear()
            self._produced_escaped = 0
            self._produce(T.Error("producer_buffer overrun"))
            return
        self._produced.append(tlv)
        self._produced_escaped += len(stuff(tlv))

    def _error(self, text: str) -> None:
        text = text[:127]
        self.errors_sent.append(text)
        self._produce(T.Error(text))

    def take_reply(self) -> bytes | None:
        """The frame the main loop sends now, or None when nothing was produced."""
        if not self._produced or self.powered_off:
            self._produced.clear()
            return None
        if self.config_reset_pending:
            self.config_reset_pending = False
            self._produce(T.ConfigReset(1))
        for c in sorted(self._charger_info_due):
            self._produce(self._charger_info(c))
        for c in sorted(self._charger_version_due):
            self._produce(T.ChargerVersion(c, 1, 2, 3))
        self._charger_info_due.clear()
        self._charger_version_due.clear()
        self._produce(self.power_source_readings())
        self._produce(T.PowerButton(int(self.power_button)))
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
                                  tuple(_int32(m.position) for m in self.motors),
                                  tuple(m.current for m in self.motors))

    @property
    def fw_major(self) -> int:
        try:
            return int(self.sw_version.split(".")[0])
        except ValueError:
            return 1


def _int32(ticks: float) -> int:
    v = math.floor(ticks)
    return (v + 2**31) % 2**32 - 2**31


def _f32(data: bytes, offset: int) -> float:
    return struct.unpack_from("<f", data, offset)[0]


# -- tag handlers: name used in error texts, expected length (None: any) ------

def _motor_ok(fw: BaseFirmware, name: str, motor: int) -> bool:
    if motor > 3:
        fw._error(f"{name} invalid motor {motor}")
        return False
    return True


def _set_motor_speed(fw, d):
    if _motor_ok(fw, "TAG_SET_MOTOR_SPEED", d[0]):
        rpm = struct.unpack_from("<h", d, 1)[0]
        fw.motors[d[0]].setpoint = rpm
        fw.setpoint_log.append((fw.now, d[0], rpm))


def _set_motor_position(fw, d):
    if _motor_ok(fw, "TAG_SET_MOTOR_POSITION", d[0]):
        fw.motors[d[0]].position = float(struct.unpack_from("<i", d, 1)[0])


def _set_pid(fw, d):
    if _motor_ok(fw, "TAG_SET_MOTOR_PID_PARAMETERS", d[0]):
        fw.motors[d[0]].kp, fw.motors[d[0]].ki = _f32(d, 1), _f32(d, 5)


def _set_odometry_rotation(fw, d):
    fw.odometry = (fw.odometry[0], fw.odometry[1], _f32(d, 0))


def _set_pwm(fw, d):
    if not 1 <= d[0] <= 6:
        fw._error(f"TAG_SET_PWM invalid channel {d[0]}")


def _set_motor_on(fw, d):
    if _motor_ok(fw, "TAG_SET_MOTOR_ON", d[0]):
        fw.motors[d[0]].on = d[1] != 0


def _set_motor_mode(fw, d):
    if _motor_ok(fw, "TAG_SET_MOTOR_MODE", d[0]):
        fw._error("TAG_SET_MOTOR_MODE not implemented")


def _reset_lpc(fw, d):
    fw.stop_all()
    fw.odometry = (0.0, 0.0, 0.0)


def _power_off(fw, d):
    fw.stop_all()
    fw.powered_off = True


def _set_accel_limits(fw, d):
    if not _motor_ok(fw, "TAG_SET_MOTOR_ACCEL_LIMITS", d[0]):
        return
    lo, hi = _f32(d, 1), _f32(d, 5)
    if lo > 0.0 or hi < lo:
        fw._error(f"TAG_SET_MOTOR_ACCEL_LIMITS invalid min {lo:f} max {hi:f} values")
        return
    fw.motors[d[0]].min_accel, fw.motors[d[0]].max_accel = lo / 1000.0, hi / 1000.0


def _get_accel_limits(fw, d):
    if _motor_ok(fw, "TAG_SET_MOTOR_ACCEL_LIMITS", d[0]):
        m = fw.motors[d[0]]
        fw._produce(T.MotorAccelLimits(d[0], 1000.0 * m.min_accel, 1000.0 * m.max_accel))


def _gyro(fw, d):
    if fw.fw_major < 2:
        fw._produce(T.GyroZAngle(fw.pose[2], fw.twist[2]))


def _gyro_data(fw, d):
    if fw.fw_major < 2:
        fw._produce(T.GyroData(((fw.t_ms & 0xFFFFFFFF, fw.twist[2]),)))


def _gyro_get_param(fw, d):
    if fw.fw_major < 2:
        fw._produce(T.GyroParam(*fw.gyro_param))


def _charger_id(fw, name, c) -> bool:
    if c > 2:
        fw._error(f"{name} invalid charger ID {c}")
        return False
    return True


def _charger_get_version(fw, d):
    if _charger_id(fw, "TAG_CHARGER_GET_VERSION", d[0]) and d[0] < fw.num_chargers:
        fw._charger_version_due.add(d[0])


def _get_gpain(fw, d):
    if not 1 <= d[0] <= 10:
        fw._error(f"TAG_GET_GPAIN invalid GPAIN {d[0]}")
    else:
        fw._produce(T.Gpain(d[0], 0.0))


def _gyro_set_param(fw, d):
    if fw.fw_major >= 2:              # the gyro was removed in 2.0.0
        return
    value = _f32(d, 1)
    if d[0] == 0:
        fw.gyro_param = (value, fw.gyro_param[1])
    elif d[0] == 1:
        fw.gyro_param = (fw.gyro_param[0], value)
    else:
        fw._error(f"TAG_GYRO_SET_PARAM invalid PARAM {d[0]}")


def _set(attr, conv=lambda d: d[0]):
    def handler(fw, d):
        setattr(fw, attr, conv(d))
    return handler


def _reply(make):
    def handler(fw, d):
        fw._produce(make(fw))
    return handler


def _noop(fw, d):
    return None


_HANDLERS: dict[int, tuple[str, int | None, object]] = {
    1: ("TAG_GET_HW_VERSION", None, _reply(lambda fw: T.HwVersion(fw.hw_version))),
    3: ("TAG_GET_SW_VERSION", None, _reply(lambda fw: T.SwVersion(fw.sw_version))),
    5: ("TAG_GET_DISTANCE_SENSOR_READINGS", None,
        _reply(lambda fw: T.DistanceSensorReadings(tuple(fw.distance)))),
    7: ("TAG_GET_ADC_PARAMETERS", None, _reply(lambda fw: T.AdcParameters(12, 3.14))),
    9: ("TAG_SET_MOTOR_SPEED", 3, _set_motor_speed),
    10: ("TAG_GET_ALL_MOTOR_SPEEDS", None,
         _reply(lambda fw: T.AllMotorSpeeds(tuple(m.measured for m in fw.motors)))),
    12: ("TAG_SET_MOTOR_POSITION", 5, _set_motor_position),
    13: ("TAG_GET_ALL_MOTOR_POSITIONS", None,
         _reply(lambda fw: T.AllMotorPositions(tuple(_int32(m.position) for m in fw.motors)))),
    15: ("TAG_SET_MOTOR_PID_PARAMETERS", 13, _set_pid),
    16: ("TAG_GET_ALL_MOTOR_PID_PARAMETERS", None, _reply(lambda fw: T.AllMotorPidParameters(
        tuple((m.kp, m.ki, 0.0) for m in fw.motors)))),
    18: ("TAG_SET_ALL_DIGITAL_OUTPUTS", 1, _set("digital_outputs")),
    19: ("TAG_SET_ALL_RELAYS", 1, _set("relays", lambda d: d[0] & 0x3)),
    20: ("TAG_SET_ODOMETRY", 12, _set("odometry", lambda d: struct.unpack("<fff", d))),
    21: ("TAG_SET_ODOMETRY", 4, _set_odometry_rotation),
    22: ("TAG_GET_ODOMETRY", None, _reply(lambda fw: T.Odometry(*fw.odometry))),
    26: ("TAG_GET_ALL_MOTOR_CURRENT_READINGS", None,
         _reply(lambda fw: T.AllMotorCurrentReadings(tuple(m.current for m in fw.motors)))),
    32: ("TAG_GET_ALL_ANALOG_INPUTS", None, _reply(lambda fw: T.AllAnalogInputs(tuple(fw.analog)))),
    34: ("TAG_GET_ALL_DIGITAL_INPUTS", None, _reply(lambda fw: T.AllDigitalInputs(fw.digital_inputs))),
    36: ("TAG_GET_BUMPER", None, _reply(lambda fw: T.Bumper(int(fw.bumper)))),
    38: ("TAG_GET_POWER_BUTTON", None, _reply(lambda fw: T.PowerButton(int(fw.power_button)))),
    40: ("TAG_SET_FPGA_POWER", 1, _set("fpga_power", lambda d: int(d[0] != 0))),
    41: ("TAG_GET_FPGA_POWER", None, _reply(lambda fw: T.FpgaPower(fw.fpga_power))),
    43: ("TAG_GET_PWR_OK_STATE", None, _reply(lambda fw: T.PwrOkState(fw.pwr_ok))),
    45: ("TAG_SET_PWR_OK_STATE", 1, _set("pwr_ok", lambda d: int(d[0] != 0))),
    46: ("TAG_SET_PWM", 2, _set_pwm),
    47: ("TAG_SET_MOTOR_ON", 2, _set_motor_on),
    48: ("TAG_SET_PWRBTN", 1, _noop),
    49: ("TAG_SET_SYS_RESET", 1, _noop),
    50: ("TAG_GET_COM_EXPRESS_STATES", None, _reply(lambda fw: T.ComExpressStates(1, 1, 1, 0, 0))),
    52: ("TAG_GET_ALL_MOTOR_READINGS", None, _reply(lambda fw: fw.motor_readings())),
    54: ("TAG_GET_IP_ADDRESS", None, _reply(lambda fw: T.IpAddress(0x7F000001, 0xFFFF0000))),
    56: ("TAG_SET_IP_ADDRESS", 8, _noop),
    57: ("TAG_SET_EMERGENCY_BUMPER", 1, _set("emergency_bumper", lambda d: d[0] != 0)),
    58: ("TAG_SET_MOTOR_MODE", 2, _set_motor_mode),
    59: ("TAG_RESET_LPC", 1, _reset_lpc),
    60: ("TAG_POWER_OFF", None, _power_off),
    61: ("TAG_SET_SAFTEY_VELCOITY", 4, _set("safety_velocity", lambda d: _f32(d, 0))),
    62: ("TAG_GET_SAFTEY_VELOCITY", None, _reply(lambda fw: T.SafteyVelocity(fw.safety_velocity))),
    66: ("TAG_SET_MOTOR_ACCEL_LIMITS", 9, _set_accel_limits),
    68: ("TAG_SET_MOTOR_ACCEL_LIMITS", 1, _get_accel_limits),
    69: ("TAG_GET_GYRO_Z_ANGLE", None, _gyro),
    71: ("TAG_GET_CAN_MSG", None, _reply(lambda fw: T.CanMsg(0, 0, bytes(8)))),
    72: ("TAG_CAN_MSG", 11, lambda fw, d: fw.can_tx.append(
        (min(struct.unpack_from("<H", d)[0], 0x7FF), min(d[2], 8), bytes(d[3:11])))),
    73: ("TAG_SET_NRST", 1, _set("nrst", lambda d: int(d[0] != 0))),
    74: ("TAG_GET_NRST", None, _reply(lambda fw: T.Nrst(fw.nrst))),
    76: ("TAG_SET_BOOT", 1, _set("boot", lambda d: d[0])),
    77: ("TAG_GET_BOOT", None, _reply(lambda fw: T.Boot(fw.boot))),
    83: ("TAG_CHARGER_GET_VERSION", 1, _charger_get_version),
    84: ("TAG_CHARGER_CLEAR_ERROR", 1, lambda fw, d: _charger_id(fw, "TAG_CHARGER_CLEAR_ERROR", d[0])),
    86: ("TAG_SET_BATTERY_MIN", 8, _set("battery_min", lambda d: struct.unpack("<ff", d))),
    87: ("TAG_GET_BATTERY_MIN", None, _reply(lambda fw: T.BatteryMin(
        fw.battery_min[1] if fw.num_chargers > 1 else fw.battery_min[0]))),
    89: ("TAG_GET_GYRODATA", None, _gyro_data),
    91: ("TAG_GET_GPAIN", 1, _get_gpain),
    93: ("TAG_GET_VERSIONBITS", None, _reply(lambda fw: T.VersionBits(0, 0))),
    95: ("TAG_GYRO_SET_PARAM", 5, _gyro_set_param),
    96: ("TAG_GYRO_GET_PARAM", None, _gyro_get_param),
}
