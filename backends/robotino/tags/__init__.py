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

The tags live by subject in :mod:`.peripherals`, :mod:`.motors` and :mod:`.power`
(their shapes in :mod:`.layout`); this package holds the registry and the
payload codec.
"""
from __future__ import annotations

import struct
from collections.abc import Iterable

from .layout import RawTag, Tag, TagError
from .motors import (
    AllMotorCurrentReadings,
    AllMotorPidParameters,
    AllMotorPositions,
    AllMotorReadings,
    AllMotorSpeeds,
    GetAllMotorCurrentReadings,
    GetAllMotorPidParameters,
    GetAllMotorPositions,
    GetAllMotorReadings,
    GetAllMotorSpeeds,
    GetGyroData,
    GetGyroZAngle,
    GetMotorAccelLimits,
    GetOdometry,
    GetSafteyVelocity,
    GyroData,
    GyroGetParam,
    GyroParam,
    GyroSetParam,
    GyroZAngle,
    MotorAccelLimits,
    MotorDebug,
    Odometry,
    SafteyVelocity,
    SetMotorAccelLimits,
    SetMotorDebug,
    SetMotorMode,
    SetMotorOn,
    SetMotorPidParameters,
    SetMotorPosition,
    SetMotorSpeed,
    SetOdometry,
    SetOdometryRotation,
    SetPwm,
    SetSafteyVelocity,
)
from .peripherals import (
    AdcParameters,
    AllAnalogInputs,
    AllDigitalInputs,
    Bumper,
    CanMsg,
    ConfigReset,
    DistanceSensorReadings,
    Error,
    GetAdcParameters,
    GetAllAnalogInputs,
    GetAllDigitalInputs,
    GetBumper,
    GetCanMsg,
    GetDistanceSensorReadings,
    GetGpain,
    GetHwVersion,
    GetIpAddress,
    GetSwVersion,
    GetVersionBits,
    Gpain,
    HwVersion,
    Info,
    IpAddress,
    SetAllDigitalOutputs,
    SetAllRelays,
    SetEmergencyBumper,
    SetIpAddress,
    SwVersion,
    VersionBits,
    Warning,
)
from .power import (
    BatteryMin,
    Boot,
    ChargerClearError,
    ChargerError,
    ChargerEvent,
    ChargerGetVersion,
    ChargerInfo,
    ChargerVersion,
    ComExpressStates,
    FestoolChargerHotswapStart,
    FestoolChargerInfo,
    FpgaPower,
    GetBatteryMin,
    GetBoot,
    GetComExpressStates,
    GetFpgaPower,
    GetNrst,
    GetPowerButton,
    GetPwrOkState,
    Nrst,
    PowerButton,
    PowerOff,
    PowerSourceReadings,
    PwrOkState,
    ResetLpc,
    SetBatteryMin,
    SetBoot,
    SetFpgaPower,
    SetNrst,
    SetPwrbtn,
    SetPwrOkState,
    SetSysReset,
)

__all__ = [
    "AdcParameters",
    "AllAnalogInputs",
    "AllDigitalInputs",
    "AllMotorCurrentReadings",
    "AllMotorPidParameters",
    "AllMotorPositions",
    "AllMotorReadings",
    "AllMotorSpeeds",
    "BatteryMin",
    "Boot",
    "Bumper",
    "CanMsg",
    "ChargerClearError",
    "ChargerError",
    "ChargerEvent",
    "ChargerGetVersion",
    "ChargerInfo",
    "ChargerVersion",
    "ComExpressStates",
    "ConfigReset",
    "DistanceSensorReadings",
    "Error",
    "FestoolChargerHotswapStart",
    "FestoolChargerInfo",
    "FpgaPower",
    "GetAdcParameters",
    "GetAllAnalogInputs",
    "GetAllDigitalInputs",
    "GetAllMotorCurrentReadings",
    "GetAllMotorPidParameters",
    "GetAllMotorPositions",
    "GetAllMotorReadings",
    "GetAllMotorSpeeds",
    "GetBatteryMin",
    "GetBoot",
    "GetBumper",
    "GetCanMsg",
    "GetComExpressStates",
    "GetDistanceSensorReadings",
    "GetFpgaPower",
    "GetGpain",
    "GetGyroData",
    "GetGyroZAngle",
    "GetHwVersion",
    "GetIpAddress",
    "GetMotorAccelLimits",
    "GetNrst",
    "GetOdometry",
    "GetPowerButton",
    "GetPwrOkState",
    "GetSafteyVelocity",
    "GetSwVersion",
    "GetVersionBits",
    "Gpain",
    "GyroData",
    "GyroGetParam",
    "GyroParam",
    "GyroSetParam",
    "GyroZAngle",
    "HwVersion",
    "Info",
    "IpAddress",
    "MotorAccelLimits",
    "MotorDebug",
    "Nrst",
    "Odometry",
    "PowerButton",
    "PowerOff",
    "PowerSourceReadings",
    "PwrOkState",
    "RawTag",
    "ResetLpc",
    "SafteyVelocity",
    "SetAllDigitalOutputs",
    "SetAllRelays",
    "SetBatteryMin",
    "SetBoot",
    "SetEmergencyBumper",
    "SetFpgaPower",
    "SetIpAddress",
    "SetMotorAccelLimits",
    "SetMotorDebug",
    "SetMotorMode",
    "SetMotorOn",
    "SetMotorPidParameters",
    "SetMotorPosition",
    "SetMotorSpeed",
    "SetNrst",
    "SetOdometry",
    "SetOdometryRotation",
    "SetPwm",
    "SetPwrOkState",
    "SetPwrbtn",
    "SetSafteyVelocity",
    "SetSysReset",
    "SwVersion",
    "Tag",
    "TagError",
    "VersionBits",
    "Warning",
    "TAGS",
    "decode_tag",
    "decode_tags",
    "encode_tags",
    "split_tlvs",
    "tag_name",
]


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
