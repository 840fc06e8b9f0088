"""Tags of versions, sensors and I/O: hardware and software versions, distance
sensors and ADC, digital and analog I/O, relays, bumper, IP address, CAN,
GPAIN, version bits and the firmware's INFO, WARNING and ERROR texts."""
from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

from .layout import Array, Flag, Request, Struct, Tag, TagError, Text, pack, unpack


@dataclass(frozen=True)
class GetHwVersion(Request):
    ID: ClassVar[int] = 1

@dataclass(frozen=True)
class HwVersion(Text):
    ID: ClassVar[int] = 2

@dataclass(frozen=True)
class GetSwVersion(Request):
    ID: ClassVar[int] = 3

@dataclass(frozen=True)
class SwVersion(Text):
    ID: ClassVar[int] = 4

@dataclass(frozen=True)
class GetDistanceSensorReadings(Request):
    ID: ClassVar[int] = 5

@dataclass(frozen=True)
class DistanceSensorReadings(Array):
    """The nine IR distance sensors' voltages (V, 0..5)."""
    ID: ClassVar[int] = 6
    FMT: ClassVar[str] = "<9f"

@dataclass(frozen=True)
class GetAdcParameters(Request):
    ID: ClassVar[int] = 7

@dataclass(frozen=True)
class AdcParameters(Struct):
    ID: ClassVar[int] = 8
    FMT: ClassVar[str] = "<Bf"
    bits: int = 12
    reference: float = 3.14

@dataclass(frozen=True)
class SetAllDigitalOutputs(Flag):
    """Bit i drives digital output i."""
    ID: ClassVar[int] = 18

@dataclass(frozen=True)
class SetAllRelays(Flag):
    """Bits 0..1 drive the two relays."""
    ID: ClassVar[int] = 19

@dataclass(frozen=True)
class GetAllAnalogInputs(Request):
    ID: ClassVar[int] = 32

@dataclass(frozen=True)
class AllAnalogInputs(Array):
    """Eight analog inputs (V, 0..10)."""
    ID: ClassVar[int] = 33
    FMT: ClassVar[str] = "<8f"

@dataclass(frozen=True)
class GetAllDigitalInputs(Request):
    ID: ClassVar[int] = 34

@dataclass(frozen=True)
class AllDigitalInputs(Flag):
    """Bit i is digital input i."""
    ID: ClassVar[int] = 35

@dataclass(frozen=True)
class GetBumper(Request):
    ID: ClassVar[int] = 36

@dataclass(frozen=True)
class Bumper(Flag):
    ID: ClassVar[int] = 37

@dataclass(frozen=True)
class GetIpAddress(Request):
    ID: ClassVar[int] = 54

@dataclass(frozen=True)
class IpAddress(Struct):
    """Address and mask as uint32 (the firmware answers a fixed dummy)."""
    ID: ClassVar[int] = 55
    FMT: ClassVar[str] = "<II"
    address: int = 0
    mask: int = 0

@dataclass(frozen=True)
class SetIpAddress(Struct):
    ID: ClassVar[int] = 56
    FMT: ClassVar[str] = "<II"
    address: int = 0
    mask: int = 0

@dataclass(frozen=True)
class SetEmergencyBumper(Flag):
    """1: the base stops all motors while the bumper is pressed."""
    ID: ClassVar[int] = 57

@dataclass(frozen=True)
class GetCanMsg(Request):
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
        return pack("<HB", self.can_id, self.dlc) + body.ljust(8, b"\0")

    @classmethod
    def from_data(cls, data: bytes):
        can_id, dlc, body = unpack("<HB8s", data)
        return cls(can_id, dlc, body)

@dataclass(frozen=True)
class ConfigReset(Flag):
    ID: ClassVar[int] = 79
    value: int = 1

@dataclass(frozen=True)
class GetGpain(Struct):
    """General-purpose analog input channel 1..10."""
    ID: ClassVar[int] = 91
    FMT: ClassVar[str] = "<B"
    channel: int = 1

@dataclass(frozen=True)
class Gpain(Struct):
    ID: ClassVar[int] = 92
    FMT: ClassVar[str] = "<Bf"
    channel: int = 1
    value: float = 0.0

@dataclass(frozen=True)
class GetVersionBits(Request):
    ID: ClassVar[int] = 93

@dataclass(frozen=True)
class VersionBits(Struct):
    ID: ClassVar[int] = 94
    FMT: ClassVar[str] = "<BB"
    bit0: int = 0
    bit1: int = 0

@dataclass(frozen=True)
class Info(Text):
    ID: ClassVar[int] = 250

@dataclass(frozen=True)
class Warning(Text):
    ID: ClassVar[int] = 251

@dataclass(frozen=True)
class Error(Text):
    ID: ClassVar[int] = 252
