"""What the base firmware does with each tag it receives (the firmware's tag
table): the name its error texts use, the data length it expects (None:
any) and the handler, called with the :class:`~.firmware.BaseFirmware` and
the tag's data.  A handler sets the firmware's state or produces a reply
tag through ``fw.produce``; a bad value gives ``fw.report_error`` a text as the
firmware prints it."""
from __future__ import annotations

import math
import struct

from . import tags as T


def int32(ticks: float) -> int:
    v = math.floor(ticks)
    return (v + 2**31) % 2**32 - 2**31


def f32(data: bytes, offset: int) -> float:
    return struct.unpack_from("<f", data, offset)[0]


# -- tag handlers: name used in error texts, expected length (None: any) ------

def _motor_ok(fw, name: str, motor: int) -> bool:
    if motor > 3:
        fw.report_error(f"{name} invalid motor {motor}")
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
        fw.motors[d[0]].kp, fw.motors[d[0]].ki = f32(d, 1), f32(d, 5)


def _set_odometry_rotation(fw, d):
    fw.odometry = (fw.odometry[0], fw.odometry[1], f32(d, 0))


def _set_pwm(fw, d):
    if not 1 <= d[0] <= 6:
        fw.report_error(f"TAG_SET_PWM invalid channel {d[0]}")


def _set_motor_on(fw, d):
    if _motor_ok(fw, "TAG_SET_MOTOR_ON", d[0]):
        fw.motors[d[0]].on = d[1] != 0


def _set_motor_mode(fw, d):
    if _motor_ok(fw, "TAG_SET_MOTOR_MODE", d[0]):
        fw.report_error("TAG_SET_MOTOR_MODE not implemented")


def _reset_lpc(fw, d):
    fw.stop_all()
    fw.odometry = (0.0, 0.0, 0.0)


def _power_off(fw, d):
    fw.stop_all()
    fw.powered_off = True


def _set_accel_limits(fw, d):
    if not _motor_ok(fw, "TAG_SET_MOTOR_ACCEL_LIMITS", d[0]):
        return
    lo, hi = f32(d, 1), f32(d, 5)
    if lo > 0.0 or hi < lo:
        fw.report_error(f"TAG_SET_MOTOR_ACCEL_LIMITS invalid min {lo:f} max {hi:f} values")
        return
    fw.motors[d[0]].min_accel, fw.motors[d[0]].max_accel = lo / 1000.0, hi / 1000.0


def _get_accel_limits(fw, d):
    if _motor_ok(fw, "TAG_SET_MOTOR_ACCEL_LIMITS", d[0]):
        m = fw.motors[d[0]]
        fw.produce(T.MotorAccelLimits(d[0], 1000.0 * m.min_accel, 1000.0 * m.max_accel))


def _gyro(fw, d):
    if fw.fw_major < 2:
        fw.produce(T.GyroZAngle(fw.pose[2], fw.twist[2]))


def _gyro_data(fw, d):
    if fw.fw_major < 2:
        fw.produce(T.GyroData(((fw.t_ms & 0xFFFFFFFF, fw.twist[2]),)))


def _gyro_get_param(fw, d):
    if fw.fw_major < 2:
        fw.produce(T.GyroParam(*fw.gyro_param))


def _charger_id(fw, name, c) -> bool:
    if c > 2:
        fw.report_error(f"{name} invalid charger ID {c}")
        return False
    return True


def _charger_get_version(fw, d):
    if _charger_id(fw, "TAG_CHARGER_GET_VERSION", d[0]) and d[0] < fw.num_chargers:
        fw._charger_version_due.add(d[0])


def _get_gpain(fw, d):
    if not 1 <= d[0] <= 10:
        fw.report_error(f"TAG_GET_GPAIN invalid GPAIN {d[0]}")
    else:
        fw.produce(T.Gpain(d[0], 0.0))


def _gyro_set_param(fw, d):
    if fw.fw_major >= 2:              # the gyro was removed in 2.0.0
        return
    value = f32(d, 1)
    if d[0] == 0:
        fw.gyro_param = (value, fw.gyro_param[1])
    elif d[0] == 1:
        fw.gyro_param = (fw.gyro_param[0], value)
    else:
        fw.report_error(f"TAG_GYRO_SET_PARAM invalid PARAM {d[0]}")


def _set(attr, conv=lambda d: d[0]):
    def handler(fw, d):
        setattr(fw, attr, conv(d))
    return handler


def _reply(make):
    def handler(fw, d):
        fw.produce(make(fw))
    return handler


def _noop(fw, d):
    return None


HANDLERS: dict[int, tuple[str, int | None, object]] = {
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
         _reply(lambda fw: T.AllMotorPositions(tuple(int32(m.position) for m in fw.motors)))),
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
    61: ("TAG_SET_SAFTEY_VELCOITY", 4, _set("safety_velocity", lambda d: f32(d, 0))),
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
