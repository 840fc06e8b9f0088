"""Tags (TLVs) of the Robotino 3 base protocol as typed values.

A payload is a list of tags ``[id:u8][len:u8][len bytes]``.  Every tag of
the firmware's table has a frozen dataclass here; numbers are little-endian,
floats IEEE-754 binary32, text ASCII without NUL.  Units: motor speeds in
motor rpm (before the 32:1 gearbox), positions in encoder ticks (2000 per
motor revolution), currents in A, voltages in V, odometry in m and rad,
accel limits in rpm/s.

``tag.encode()`` gives the TLV bytes; :func:`decode_tags` turns a payload
into tags and never raises: an unknown id or a layout that does not fit
becomes a :class:`RawTag` (with ``reason``), a length running past the end
of the payload a :class:`RawTag` marked ``truncated``.
"""
from __future__ import annotations

import struct
from collections.abc import Iterable
from dataclasses import dataclass, fields
from typing import ClassVar


class TagError(ValueError):
    """A value does not fit its tag's layout."""


@dataclass(frozen=True)
class Tag:
    """Base of all tags.  Subclasses set ``ID``."""
    ID: ClassVar[int] = -1

    def data(self) -> bytes:
        return b""

    @classmethod
    def from_data(cls, data: bytes) -> Tag:
        return cls()

    def encode(self) -> bytes:
        d = self.data()
        if len(d) > 255:
            raise TagError(f"{type(self).__name__}: {len(d)} data bytes do not fit a tag")
        return bytes((self.ID, len(d))) + d


@dataclass(frozen=True)
class RawTag(Tag):
    """A tag this module does not type (unknown id or unexpected layout)."""
    tag_id: int = 0
    raw: bytes = b""
    reason: str = ""
    truncated: bool = False

    def data(self) -> bytes:
        return bytes(self.raw)

    def encode(self) -> bytes:
        return bytes((self.tag_id, len(self.raw))) + bytes(self.raw)


# -- layout helpers -----------------------------------------------------------

def _pack(fmt: str, *values) -> bytes:
    try:
        return struct.pack(fmt, *values)
    except (struct.error, OverflowError, TypeError) as exc:
        raise TagError(f"cannot pack {values!r} as {fmt!r}: {exc}") from None


def _unpack(fmt: str, data: bytes) -> tuple:
    if len(data) != struct.calcsize(fmt):
        raise TagError(f"expected {struct.calcsize(fmt)} data bytes, got {len(data)}")
    return struct.unpack(fmt, data)


def _unpack_head(fmt: str, data: bytes) -> tuple[tuple, bytes]:
    """Unpack a fixed head and return it with the variable rest."""
    size = struct.calcsize(fmt)
    if len(data) < size:
        raise TagError(f"expected at least {size} data bytes, got {len(data)}")
    return struct.unpack_from(fmt, data), bytes(data[size:])


def _text(data: bytes) -> str:
    return bytes(data).decode("latin-1")


def _ascii(text: str) -> bytes:
    try:
        return text.encode("latin-1")
    except UnicodeEncodeError as exc:
        raise TagError(f"text {text!r} is not 8-bit: {exc}") from None


@dataclass(frozen=True)
class _Request(Tag):
    """A tag without data (a GET).  The firmware ignores data sent with one."""


@dataclass(frozen=True)
class _Struct(Tag):
    """Fields map one to one onto the struct format ``FMT``."""
    FMT: ClassVar[str] = "<"

    def data(self) -> bytes:
        return _pack(self.FMT, *(getattr(self, f.name) for f in fields(self)))

    @classmethod
    def from_data(cls, data: bytes):
        return cls(*_unpack(cls.FMT, data))


@dataclass(frozen=True)
class _Array(Tag):
    """One tuple field ``values`` packed as ``FMT`` (e.g. ``"<9f"``)."""
    FMT: ClassVar[str] = "<"
    values: tuple = ()

    def data(self) -> bytes:
        return _pack(self.FMT, *self.values)

    @classmethod
    def from_data(cls, data: bytes):
        return cls(tuple(_unpack(cls.FMT, data)))


@dataclass(frozen=True)
class _Text(Tag):
    text: str = ""

    def data(self) -> bytes:
        return _ascii(self.text)

    @classmethod
    def from_data(cls, data: bytes):
        return cls(_text(data))


@dataclass(frozen=True)
class _Flag(_Struct):
    """A single unsigned byte."""
    FMT: ClassVar[str] = "<B"
    value: int = 0


# -- the table ----------------------------------------------------------------

@dataclass(frozen=True)
class GetHwVersion(_Request):
    ID: ClassVar[int] = 1


@dataclass(frozen=True)
class HwVersion(_Text):
    ID: ClassVar[int] = 2


@dataclass(frozen=True)
class GetSwVersion(_Request):
    ID: ClassVar[int] = 3


@dataclass(frozen=True)
class SwVersion(_Text):
    ID: ClassVar[int] = 4


@dataclass(frozen=True)
class GetDistanceSensorReadings(_Request):
    ID: ClassVar[int] = 5


@dataclass(frozen=True)
class DistanceSensorReadings(_Array):
    """The nine IR distance sensors' voltages (V, 0..5)."""
    ID: ClassVar[int] = 6
    FMT: ClassVar[str] = "<9f"


@dataclass(frozen=True)
class GetAdcParameters(_Request):
    ID: ClassVar[int] = 7


@dataclass(frozen=True)
class AdcParameters(_Struct):
    ID: ClassVar[int] = 8
    FMT: ClassVar[str] = "<Bf"
    bits: int = 12
    reference: float = 3.14


@dataclass(frozen=True)
class SetMotorSpeed(_Struct):
    """Set-point of one motor in motor rpm (int16, two's complement)."""
    ID: ClassVar[int] = 9
    FMT: ClassVar[str] = "<Bh"
    motor: int = 0
    rpm: int = 0


@dataclass(frozen=True)
class GetAllMotorSpeeds(_Request):
    ID: ClassVar[int] = 10


@dataclass(frozen=True)
class AllMotorSpeeds(_Array):
    ID: ClassVar[int] = 11
    FMT: ClassVar[str] = "<4h"


@dataclass(frozen=True)
class SetMotorPosition(_Struct):
    ID: ClassVar[int] = 12
    FMT: ClassVar[str] = "<Bi"
    motor: int = 0
    position: int = 0


@dataclass(frozen=True)
class GetAllMotorPositions(_Request):
    ID: ClassVar[int] = 13


@dataclass(frozen=True)
class AllMotorPositions(_Array):
    ID: ClassVar[int] = 14
    FMT: ClassVar[str] = "<4i"


@dataclass(frozen=True)
class SetMotorPidParameters(_Struct):
    """kp, ki, kd of one motor (the firmware ignores kd)."""
    ID: ClassVar[int] = 15
    FMT: ClassVar[str] = "<Bfff"
    motor: int = 0
    kp: float = 0.0
    ki: float = 0.0
    kd: float = 0.0


@dataclass(frozen=True)
class GetAllMotorPidParameters(_Request):
    ID: ClassVar[int] = 16


@dataclass(frozen=True)
class AllMotorPidParameters(Tag):
    """Four (kp, ki, kd) triples; the firmware always sends kd = 0."""
    ID: ClassVar[int] = 17
    params: tuple = ((0.0, 0.0, 0.0),) * 4

    def data(self) -> bytes:
        flat = [v for triple in self.params for v in triple]
        return _pack("<12f", *flat)

    @classmethod
    def from_data(cls, data: bytes):
        v = _unpack("<12f", data)
        return cls(tuple(tuple(v[i:i + 3]) for i in range(0, 12, 3)))


@dataclass(frozen=True)
class SetAllDigitalOutputs(_Flag):
    """Bit i drives digital output i."""
    ID: ClassVar[int] = 18


@dataclass(frozen=True)
class SetAllRelays(_Flag):
    """Bits 0..1 drive the two relays."""
    ID: ClassVar[int] = 19


@dataclass(frozen=True)
class SetOdometry(_Struct):
    ID: ClassVar[int] = 20
    FMT: ClassVar[str] = "<fff"
    x: float = 0.0
    y: float = 0.0
    phi: float = 0.0


@dataclass(frozen=True)
class SetOdometryRotation(_Struct):
    ID: ClassVar[int] = 21
    FMT: ClassVar[str] = "<f"
    phi: float = 0.0


@dataclass(frozen=True)
class GetOdometry(_Request):
    ID: ClassVar[int] = 22


@dataclass(frozen=True)
class Odometry(_Struct):
    """The firmware's stored odometry (it never integrates it itself)."""
    ID: ClassVar[int] = 23
    FMT: ClassVar[str] = "<fff"
    x: float = 0.0
    y: float = 0.0
    phi: float = 0.0


@dataclass(frozen=True)
class GetAllMotorCurrentReadings(_Request):
    ID: ClassVar[int] = 26


@dataclass(frozen=True)
class AllMotorCurrentReadings(_Array):
    ID: ClassVar[int] = 27
    FMT: ClassVar[str] = "<4f"


@dataclass(frozen=True)
class GetAllAnalogInputs(_Request):
    ID: ClassVar[int] = 32


@dataclass(frozen=True)
class AllAnalogInputs(_Array):
    """Eight analog inputs (V, 0..10)."""
    ID: ClassVar[int] = 33
    FMT: ClassVar[str] = "<8f"


@dataclass(frozen=True)
class GetAllDigitalInputs(_Request):
    ID: ClassVar[int] = 34


@dataclass(frozen=True)
class AllDigitalInputs(_Flag):
    """Bit i is digital input i."""
    ID: ClassVar[int] = 35


@dataclass(frozen=True)
class GetBumper(_Request):
    ID: ClassVar[int] = 36


@dataclass(frozen=True)
class Bumper(_Flag):
    ID: ClassVar[int] = 37


@dataclass(frozen=True)
class GetPowerButton(_Request):
    ID: ClassVar[int] = 38


@dataclass(frozen=True)
class PowerButton(_Flag):
    ID: ClassVar[int] = 39


@dataclass(frozen=True)
class SetFpgaPower(_Flag):
    ID: ClassVar[int] = 40


@dataclass(frozen=True)
class GetFpgaPower(_Request):
    ID: ClassVar[int] = 41


@dataclass(frozen=True)
class FpgaPower(_Flag):
    ID: ClassVar[int] = 42


@dataclass(frozen=True)
class GetPwrOkState(_Request):
    ID: ClassVar[int] = 43


@dataclass(frozen=True)
class PwrOkState(_Flag):
    ID: ClassVar[int] = 44


@dataclass(frozen=True)
class SetPwrOkState(_Flag):
    ID: ClassVar[int] = 45


@dataclass(frozen=True)
class SetPwm(_Struct):
    """PWM channel 1..6, duty ratio 0..255."""
    ID: ClassVar[int] = 46
    FMT: ClassVar[str] = "<BB"
    channel: int = 1
    ratio: int = 0


@dataclass(frozen=True)
class SetMotorOn(_Struct):
    ID: ClassVar[int] = 47
    FMT: ClassVar[str] = "<BB"
    motor: int = 0
    on: int = 1


@dataclass(frozen=True)
class SetPwrbtn(_Flag):
    ID: ClassVar[int] = 48


@dataclass(frozen=True)
class SetSysReset(_Flag):
    ID: ClassVar[int] = 49


@dataclass(frozen=True)
class GetComExpressStates(_Request):
    ID: ClassVar[int] = 50


@dataclass(frozen=True)
class ComExpressStates(_Struct):
    ID: ClassVar[int] = 51
    FMT: ClassVar[str] = "<5B"
    sus_s3: int = 0
    sus_s4: int = 0
    sus_s5: int = 0
    thrm: int = 0
    thrmtrip: int = 0


@dataclass(frozen=True)
class GetAllMotorReadings(_Request):
    ID: ClassVar[int] = 52


@dataclass(frozen=True)
class AllMotorReadings(Tag):
    """4 speeds (int16 rpm), 4 positions (int32 ticks), 4 currents (float A)."""
    ID: ClassVar[int] = 53
    speeds: tuple = (0, 0, 0, 0)
    positions: tuple = (0, 0, 0, 0)
    currents: tuple = (0.0, 0.0, 0.0, 0.0)

    def data(self) -> bytes:
        return _pack("<4h4i4f", *self.speeds, *self.positions, *self.currents)

    @classmethod
    def from_data(cls, data: bytes):
        v = _unpack("<4h4i4f", data)
        return cls(tuple(v[0:4]), tuple(v[4:8]), tuple(v[8:12]))


@dataclass(frozen=True)
class GetIpAddress(_Request):
    ID: ClassVar[int] = 54


@dataclass(frozen=True)
class IpAddress(_Struct):
    """Address and mask as uint32 (the firmware answers a fixed dummy)."""
    ID: ClassVar[int] = 55
    FMT: ClassVar[str] = "<II"
    address: int = 0
    mask: int = 0


@dataclass(frozen=True)
class SetIpAddress(_Struct):
    ID: ClassVar[int] = 56
    FMT: ClassVar[str] = "<II"
    address: int = 0
    mask: int = 0


@dataclass(frozen=True)
class SetEmergencyBumper(_Flag):
    """1: the base stops all motors while the bumper is pressed."""
    ID: ClassVar[int] = 57


@dataclass(frozen=True)
class SetMotorMode(_Struct):
    ID: ClassVar[int] = 58
    FMT: ClassVar[str] = "<BB"
    motor: int = 0
    mode: int = 0


@dataclass(frozen=True)
class ResetLpc(_Flag):
    """value 1: enter the USB bootloader."""
    ID: ClassVar[int] = 59


@dataclass(frozen=True)
class PowerOff(_Request):
    ID: ClassVar[int] = 60


@dataclass(frozen=True)
class SetSafteyVelocity(_Struct):
    """Safety velocity in rpm (spelled as in the firmware)."""
    ID: ClassVar[int] = 61
    FMT: ClassVar[str] = "<f"
    rpm: float = 400.0


@dataclass(frozen=True)
class GetSafteyVelocity(_Request):
    ID: ClassVar[int] = 62


@dataclass(frozen=True)
class SafteyVelocity(_Struct):
    ID: ClassVar[int] = 63
    FMT: ClassVar[str] = "<f"
    rpm: float = 400.0


@dataclass(frozen=True)
class PowerSourceReadings(_Struct):
    """Sent with every reply.  battery_type: 0 Pb, 1 NiMH."""
    ID: ClassVar[int] = 65
    FMT: ClassVar[str] = "<ffBBBBI"
    voltage: float = 0.0
    current: float = 0.0
    ext_power: int = 0
    num_chargers: int = 0
    battery_type: int = 0
    battery_low: int = 0
    battery_low_count: int = 0


@dataclass(frozen=True)
class SetMotorAccelLimits(_Struct):
    """min <= 0 <= ... and max >= min, in rpm/s (the base stores them / 1000)."""
    ID: ClassVar[int] = 66
    FMT: ClassVar[str] = "<Bff"
    motor: int = 0
    min_accel: float = -12000.0
    max_accel: float = 12000.0


@dataclass(frozen=True)
class MotorAccelLimits(_Struct):
    ID: ClassVar[int] = 67
    FMT: ClassVar[str] = "<Bff"
    motor: int = 0
    min_accel: float = -12000.0
    max_accel: float = 12000.0


@dataclass(frozen=True)
class GetMotorAccelLimits(_Struct):
    ID: ClassVar[int] = 68
    FMT: ClassVar[str] = "<B"
    motor: int = 0


@dataclass(frozen=True)
class GetGyroZAngle(_Request):
    ID: ClassVar[int] = 69


@dataclass(frozen=True)
class GyroZAngle(_Struct):
    """Gyro angle and rate as sent (the firmware negates both)."""
    ID: ClassVar[int] = 70
    FMT: ClassVar[str] = "<ff"
    angle: float = 0.0
    rate: float = 0.0


@dataclass(frozen=True)
class GetCanMsg(_Request):
    ID: ClassVar[int] = 71


@dataclass(frozen=True)
class CanMsg(Tag):
    """A CAN frame: 11-bit id, dlc, always 8 data bytes on the wire."""
    ID: ClassVar[int] = 72
    can_id: int = 0
    dlc: int = 0
    payload: bytes = bytes(8)

    def data(self) -> bytes:
        body = bytes(self.payload)
        if len(body) > 8:
            raise TagError(f"CAN payload of {len(body)} bytes (max 8)")
        return _pack("<HB", self.can_id, self.dlc) + body.ljust(8, b"\0")

    @classmethod
    def from_data(cls, data: bytes):
        can_id, dlc, body = _unpack("<HB8s", data)
        return cls(can_id, dlc, body)


@dataclass(frozen=True)
class SetNrst(_Flag):
    ID: ClassVar[int] = 73


@dataclass(frozen=True)
class GetNrst(_Request):
    ID: ClassVar[int] = 74


@dataclass(frozen=True)
class Nrst(_Flag):
    ID: ClassVar[int] = 75


@dataclass(frozen=True)
class SetBoot(_Flag):
    ID: ClassVar[int] = 76


@dataclass(frozen=True)
class GetBoot(_Request):
    ID: ClassVar[int] = 77


@dataclass(frozen=True)
class Boot(_Flag):
    ID: ClassVar[int] = 78


@dataclass(frozen=True)
class ConfigReset(_Flag):
    ID: ClassVar[int] = 79
    value: int = 1


@dataclass(frozen=True)
class ChargerInfo(Tag):
    """Charger state: time (s), battery voltage (V), current (A), two
    temperatures, state number and state text."""
    ID: ClassVar[int] = 80
    charger: int = 0
    time: int = 0
    voltage: float = 0.0
    current: float = 0.0
    temp1: float = 0.0
    temp2: float = 0.0
    state: int = 0
    state_text: str = ""

    def data(self) -> bytes:
        return _pack("<BIffffB", self.charger, self.time, self.voltage, self.current,
                     self.temp1, self.temp2, self.state) + _ascii(self.state_text)

    @classmethod
    def from_data(cls, data: bytes):
        head, rest = _unpack_head("<BIffffB", data)
        return cls(*head, _text(rest))


@dataclass(frozen=True)
class ChargerEvent(Tag):
    """Defined by the firmware but never filled; kept as raw bytes."""
    ID: ClassVar[int] = 81
    raw: bytes = b""

    def data(self) -> bytes:
        return bytes(self.raw)

    @classmethod
    def from_data(cls, data: bytes):
        return cls(bytes(data))


@dataclass(frozen=True)
class ChargerVersion(_Struct):
    ID: ClassVar[int] = 82
    FMT: ClassVar[str] = "<BBBB"
    charger: int = 0
    major: int = 0
    minor: int = 0
    patch: int = 0


@dataclass(frozen=True)
class ChargerGetVersion(_Struct):
    ID: ClassVar[int] = 83
    FMT: ClassVar[str] = "<B"
    charger: int = 0


@dataclass(frozen=True)
class ChargerClearError(_Struct):
    ID: ClassVar[int] = 84
    FMT: ClassVar[str] = "<B"
    charger: int = 0


@dataclass(frozen=True)
class ChargerError(Tag):
    ID: ClassVar[int] = 85
    charger: int = 0
    time: int = 0
    text: str = ""

    def data(self) -> bytes:
        return _pack("<BI", self.charger, self.time) + _ascii(self.text)

    @classmethod
    def from_data(cls, data: bytes):
        (charger, time), rest = _unpack_head("<BI", data)
        return cls(charger, time, _text(rest))


@dataclass(frozen=True)
class SetBatteryMin(_Struct):
    """Minimum battery voltages (V) for lead-acid and NiMH packs."""
    ID: ClassVar[int] = 86
    FMT: ClassVar[str] = "<ff"
    pb_min: float = 19.0
    nimh_min: float = 19.8


@dataclass(frozen=True)
class GetBatteryMin(_Request):
    ID: ClassVar[int] = 87


@dataclass(frozen=True)
class BatteryMin(_Struct):
    ID: ClassVar[int] = 88
    FMT: ClassVar[str] = "<f"
    voltage: float = 0.0


@dataclass(frozen=True)
class GetGyroData(_Request):
    ID: ClassVar[int] = 89


@dataclass(frozen=True)
class GyroData(Tag):
    """Samples of (timestamp u32, rate float)."""
    ID: ClassVar[int] = 90
    samples: tuple = ()

    def data(self) -> bytes:
        return b"".join(_pack("<If", stamp, rate) for stamp, rate in self.samples)

    @classmethod
    def from_data(cls, data: bytes):
        if len(data) % 8:
            raise TagError(f"{len(data)} bytes are not whole (u32, float) samples")
        return cls(tuple(struct.unpack_from("<If", data, i) for i in range(0, len(data), 8)))


@dataclass(frozen=True)
class GetGpain(_Struct):
    """General-purpose analog input channel 1..10."""
    ID: ClassVar[int] = 91
    FMT: ClassVar[str] = "<B"
    channel: int = 1


@dataclass(frozen=True)
class Gpain(_Struct):
    ID: ClassVar[int] = 92
    FMT: ClassVar[str] = "<Bf"
    channel: int = 1
    value: float = 0.0


@dataclass(frozen=True)
class GetVersionBits(_Request):
    ID: ClassVar[int] = 93


@dataclass(frozen=True)
class VersionBits(_Struct):
    ID: ClassVar[int] = 94
    FMT: ClassVar[str] = "<BB"
    bit0: int = 0
    bit1: int = 0


@dataclass(frozen=True)
class GyroSetParam(_Struct):
    """param 0: bias, 1: scale."""
    ID: ClassVar[int] = 95
    FMT: ClassVar[str] = "<Bf"
    param: int = 0
    value: float = 0.0


@dataclass(frozen=True)
class GyroGetParam(_Request):
    ID: ClassVar[int] = 96


@dataclass(frozen=True)
class GyroParam(_Struct):
    ID: ClassVar[int] = 97
    FMT: ClassVar[str] = "<ff"
    bias: float = 0.0
    scale: float = 1.0


@dataclass(frozen=True)
class FestoolChargerInfo(Tag):
    """fw 2.x: time, accu load/connect bits, flags (bit0 external power,
    bit1 charger present), 4 accu voltages (mV), 4 capacities (%), text."""
    ID: ClassVar[int] = 98
    time: int = 0
    accu_bits: int = 0
    flags: int = 0
    voltages_mv: tuple = (0, 0, 0, 0)
    capacities: tuple = (0, 0, 0, 0)
    text: str = ""

    def data(self) -> bytes:
        return _pack("<IBB4H4B", self.time, self.accu_bits, self.flags, *self.voltages_mv,
                     *self.capacities) + _ascii(self.text)

    @classmethod
    def from_data(cls, data: bytes):
        v, rest = _unpack_head("<IBB4H4B", data)
        return cls(v[0], v[1], v[2], tuple(v[3:7]), tuple(v[7:11]), _text(rest))


@dataclass(frozen=True)
class FestoolChargerHotswapStart(_Request):
    ID: ClassVar[int] = 99


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
        return _pack("<BIB", self.motor, self.start_time, self.time_delta) + b"".join(
            _pack("<4h", *s) for s in self.samples)

    @classmethod
    def from_data(cls, data: bytes):
        head, rest = _unpack_head("<BIB", data)
        if len(rest) % 8:
            raise TagError(f"{len(rest)} sample bytes are not whole 4 x int16 samples")
        return cls(*head, tuple(struct.unpack_from("<4h", rest, i) for i in range(0, len(rest), 8)))


@dataclass(frozen=True)
class SetMotorDebug(_Flag):
    """0 off, 1..4 debug motor 0..3."""
    ID: ClassVar[int] = 101


@dataclass(frozen=True)
class Info(_Text):
    ID: ClassVar[int] = 250


@dataclass(frozen=True)
class Warning(_Text):
    ID: ClassVar[int] = 251


@dataclass(frozen=True)
class Error(_Text):
    ID: ClassVar[int] = 252


# -- registry and payload codec ----------------------------------------------

def _all_tag_classes() -> dict[int, type]:
    out: dict[int, type] = {}
    for obj in list(globals().values()):
        if isinstance(obj, type) and issubclass(obj, Tag) and obj.ID >= 0:
            if obj.ID in out:
                raise RuntimeError(f"tag id {obj.ID} defined twice")
            out[obj.ID] = obj
    return dict(sorted(out.items()))


#: tag id -> typed class, for every tag of the firmware table
TAGS: dict[int, type] = _all_tag_classes()

def tag_name(tag_id: int) -> str:
    """The firmware's name of a tag id, e.g. 9 -> ``SET_MOTOR_SPEED``."""
    cls = TAGS.get(tag_id)
    if cls is None:
        return f"TAG_{tag_id}"
    name = cls.__name__
    return "".join("_" + c if c.isupper() and i else c for i, c in enumerate(name)).upper()


def encode_tags(tags: Iterable[Tag | bytes]) -> bytes:
    """Concatenate tags (or pre-encoded TLV bytes) into a payload."""
    return b"".join(t if isinstance(t, (bytes, bytearray)) else t.encode() for t in tags)


def split_tlvs(payload: bytes) -> tuple[list[tuple[int, bytes]], tuple[int, int, int] | None]:
    """Walk a payload the way the firmware parser does.

    Returns the ``(id, data)`` pairs and, if a tag's length runs past the end,
    ``(id, tag_length, remaining_payload_length)`` of that tag (the walk stops
    there, like the firmware).  A single trailing byte is ignored.
    """
    out: list[tuple[int, bytes]] = []
    i, n = 0, len(payload)
    while n - i >= 2:
        tag_id, tag_len = payload[i], payload[i + 1]
        if tag_len > n - i - 2:
            return out, (tag_id, tag_len, n - i)
        out.append((tag_id, bytes(payload[i + 2:i + 2 + tag_len])))
        i += 2 + tag_len
    return out, None


def decode_tag(tag_id: int, data: bytes) -> Tag:
    """One typed tag; a :class:`RawTag` when the id is unknown or the data
    does not fit.  Never raises."""
    cls = TAGS.get(tag_id)
    if cls is None:
        return RawTag(tag_id, bytes(data), "unknown tag id")
    try:
        return cls.from_data(bytes(data))
    except (TagError, struct.error, ValueError) as exc:
        return RawTag(tag_id, bytes(data), f"{cls.__name__}: {exc}")


def decode_tags(payload: bytes) -> list[Tag]:
    """All tags of a payload (see the module docstring).  Never raises."""
    pairs, overflow = split_tlvs(payload)
    tags = [decode_tag(i, d) for i, d in pairs]
    if overflow is not None:
        tag_id, tag_len, remaining = overflow
        start = len(payload) - remaining
        tags.append(RawTag(tag_id, bytes(payload[start + 2:]),
                           f"tag length {tag_len} runs past the payload end", truncated=True))
    return tags
