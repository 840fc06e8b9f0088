"""Tags of the motors, odometry and gyro: speeds, positions, PID and accel
limits, currents, the all-motor readings, the safety velocity and the gyro."""
from __future__ import annotations

import struct
from dataclasses import dataclass
from typing import ClassVar

from .layout import Array, Flag, Request, Struct, Tag, TagError, pack, unpack, unpack_head


@dataclass(frozen=True)
class SetMotorSpeed(Struct):
    """Set-point of one motor in motor rpm (int16, two's complement)."""
    ID: ClassVar[int] = 9
    FMT: ClassVar[str] = "<Bh"
    motor: int = 0
    rpm: int = 0

@dataclass(frozen=True)
class GetAllMotorSpeeds(Request):
    ID: ClassVar[int] = 10

@dataclass(frozen=True)
class AllMotorSpeeds(Array):
    ID: ClassVar[int] = 11
    FMT: ClassVar[str] = "<4h"

@dataclass(frozen=True)
class SetMotorPosition(Struct):
    ID: ClassVar[int] = 12
    FMT: ClassVar[str] = "<Bi"
    motor: int = 0
    position: int = 0

@dataclass(frozen=True)
class GetAllMotorPositions(Request):
    ID: ClassVar[int] = 13

@dataclass(frozen=True)
class AllMotorPositions(Array):
    ID: ClassVar[int] = 14
    FMT: ClassVar[str] = "<4i"

@dataclass(frozen=True)
class SetMotorPidParameters(Struct):
    """kp, ki, kd of one motor (the firmware ignores kd)."""
    ID: ClassVar[int] = 15
    FMT: ClassVar[str] = "<Bfff"
    motor: int = 0
    kp: float = 0.0
    ki: float = 0.0
    kd: float = 0.0

@dataclass(frozen=True)
class GetAllMotorPidParameters(Request):
    ID: ClassVar[int] = 16

@dataclass(frozen=True)
class AllMotorPidParameters(Tag):
    """Four (kp, ki, kd) triples; the firmware always sends kd = 0."""
    ID: ClassVar[int] = 17
    params: tuple = ((0.0, 0.0, 0.0),) * 4

    def data(self) -> bytes:
        flat = [v for triple in self.params for v in triple]
        return pack("<12f", *flat)

    @classmethod
    def from_data(cls, data: bytes):
        v = unpack("<12f", data)
        return cls(tuple(tuple(v[i:i + 3]) for i in range(0, 12, 3)))

@dataclass(frozen=True)
class SetOdometry(Struct):
    ID: ClassVar[int] = 20
    FMT: ClassVar[str] = "<fff"
    x: float = 0.0
    y: float = 0.0
    phi: float = 0.0

@dataclass(frozen=True)
class SetOdometryRotation(Struct):
    ID: ClassVar[int] = 21
    FMT: ClassVar[str] = "<f"
    phi: float = 0.0

@dataclass(frozen=True)
class GetOdometry(Request):
    ID: ClassVar[int] = 22

@dataclass(frozen=True)
class Odometry(Struct):
    """The firmware's stored odometry (it never integrates it itself)."""
    ID: ClassVar[int] = 23
    FMT: ClassVar[str] = "<fff"
    x: float = 0.0
    y: float = 0.0
    phi: float = 0.0

@dataclass(frozen=True)
class GetAllMotorCurrentReadings(Request):
    ID: ClassVar[int] = 26

@dataclass(frozen=True)
class AllMotorCurrentReadings(Array):
    ID: ClassVar[int] = 27
    FMT: ClassVar[str] = "<4f"

@dataclass(frozen=True)
class SetPwm(Struct):
    """PWM channel 1..6, duty ratio 0..255."""
    ID: ClassVar[int] = 46
    FMT: ClassVar[str] = "<BB"
    channel: int = 1
    ratio: int = 0

@dataclass(frozen=True)
class SetMotorOn(Struct):
    ID: ClassVar[int] = 47
    FMT: ClassVar[str] = "<BB"
    motor: int = 0
    on: int = 1

@dataclass(frozen=True)
class GetAllMotorReadings(Request):
    ID: ClassVar[int] = 52

@dataclass(frozen=True)
class AllMotorReadings(Tag):
    """4 speeds (int16 rpm), 4 positions (int32 ticks), 4 currents (float A)."""
    ID: ClassVar[int] = 53
    speeds: tuple = (0, 0, 0, 0)
    positions: tuple = (0, 0, 0, 0)
    currents: tuple = (0.0, 0.0, 0.0, 0.0)

    def data(self) -> bytes:
        return pack("<4h4i4f", *self.speeds, *self.positions, *self.currents)

    @classmethod
    def from_data(cls, data: bytes):
        v = unpack("<4h4i4f", data)
        return cls(tuple(v[0:4]), tuple(v[4:8]), tuple(v[8:12]))

@dataclass(frozen=True)
class SetMotorMode(Struct):
    ID: ClassVar[int] = 58
    FMT: ClassVar[str] = "<BB"
    motor: int = 0
    mode: int = 0

@dataclass(frozen=True)
class SetSafteyVelocity(Struct):
    """Safety velocity in rpm (spelled as in the firmware)."""
    ID: ClassVar[int] = 61
    FMT: ClassVar[str] = "<f"
    rpm: float = 400.0

@dataclass(frozen=True)
class GetSafteyVelocity(Request):
    ID: ClassVar[int] = 62

@dataclass(frozen=True)
class SafteyVelocity(Struct):
    ID: ClassVar[int] = 63
    FMT: ClassVar[str] = "<f"
    rpm: float = 400.0

@dataclass(frozen=True)
class SetMotorAccelLimits(Struct):
    """min <= 0 <= ... and max >= min, in rpm/s (the base stores them / 1000)."""
    ID: ClassVar[int] = 66
    FMT: ClassVar[str] = "<Bff"
    motor: int = 0
    min_accel: float = -12000.0
    max_accel: float = 12000.0

@dataclass(frozen=True)
class MotorAccelLimits(Struct):
    ID: ClassVar[int] = 67
    FMT: ClassVar[str] = "<Bff"
    motor: int = 0
    min_accel: float = -12000.0
    max_accel: float = 12000.0

@dataclass(frozen=True)
class GetMotorAccelLimits(Struct):
    ID: ClassVar[int] = 68
    FMT: ClassVar[str] = "<B"
    motor: int = 0

@dataclass(frozen=True)
class GetGyroZAngle(Request):
    ID: ClassVar[int] = 69

@dataclass(frozen=True)
class GyroZAngle(Struct):
    """Gyro angle and rate as sent (the firmware negates both)."""
    ID: ClassVar[int] = 70
    FMT: ClassVar[str] = "<ff"
    angle: float = 0.0
    rate: float = 0.0

@dataclass(frozen=True)
class GetGyroData(Request):
    ID: ClassVar[int] = 89

@dataclass(frozen=True)
class GyroData(Tag):
    """Samples of (timestamp u32, rate float)."""
    ID: ClassVar[int] = 90
    samples: tuple = ()

    def data(self) -> bytes:
        return b"".join(pack("<If", stamp, rate) for stamp, rate in self.samples)

    @classmethod
    def from_data(cls, data: bytes):
        if len(data) % 8:
            raise TagError(f"{len(data)} bytes are not whole (u32, float) samples")
        return cls(tuple(struct.unpack_from("<If", data, i) for i in range(0, len(data), 8)))

@dataclass(frozen=True)
class GyroSetParam(Struct):
    """param 0: bias, 1: scale."""
    ID: ClassVar[int] = 95
    FMT: ClassVar[str] = "<Bf"
    param: int = 0
    value: float = 0.0

@dataclass(frozen=True)
class GyroGetParam(Request):
    ID: ClassVar[int] = 96

@dataclass(frozen=True)
class GyroParam(Struct):
    ID: ClassVar[int] = 97
    FMT: ClassVar[str] = "<ff"
    bias: float = 0.0
    scale: float = 1.0

@dataclass(frozen=True)
class MotorDebug(Tag):
    """fw 2.x: motor, start time, sample spacing (0.1 ms), then samples of
    (set-point rpm, speed rpm, current mA, control point) as int16."""
    ID: ClassVar[int] = 100
    motor: int = 0
    start_time: int = 0
    time_delta: int = 0
    samples: tuple = ()

    def data(self) -> bytes:
        return pack("<BIB", self.motor, self.start_time, self.time_delta) + b"".join(
            pack("<4h", *s) for s in self.samples)

    @classmethod
    def from_data(cls, data: bytes):
        head, rest = unpack_head("<BIB", data)
        if len(rest) % 8:
            raise TagError(f"{len(rest)} sample bytes are not whole 4 x int16 samples")
        return cls(*head, tuple(struct.unpack_from("<4h", rest, i) for i in range(0, len(rest), 8)))

@dataclass(frozen=True)
class SetMotorDebug(Flag):
    """0 off, 1..4 debug motor 0..3."""
    ID: ClassVar[int] = 101
