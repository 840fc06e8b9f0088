"""Tags of power and boot: power source readings, power button, FPGA power,
PWR_OK, NRST and BOOT lines, reset and power off, the COM Express states,
the chargers and the battery minimum."""
from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

from .layout import Flag, Request, Struct, Tag, ascii_bytes, latin1, pack, unpack_head


@dataclass(frozen=True)
class SetFpgaPower(Flag):
    ID: ClassVar[int] = 40

@dataclass(frozen=True)
class GetFpgaPower(Request):
    ID: ClassVar[int] = 41

@dataclass(frozen=True)
class FpgaPower(Flag):
    ID: ClassVar[int] = 42

@dataclass(frozen=True)
class GetPwrOkState(Request):
    ID: ClassVar[int] = 43

@dataclass(frozen=True)
class PwrOkState(Flag):
    ID: ClassVar[int] = 44

@dataclass(frozen=True)
class SetPwrOkState(Flag):
    ID: ClassVar[int] = 45

@dataclass(frozen=True)
class SetPwrbtn(Flag):
    ID: ClassVar[int] = 48

@dataclass(frozen=True)
class SetSysReset(Flag):
    ID: ClassVar[int] = 49

@dataclass(frozen=True)
class GetComExpressStates(Request):
    ID: ClassVar[int] = 50

@dataclass(frozen=True)
class ComExpressStates(Struct):
    ID: ClassVar[int] = 51
    FMT: ClassVar[str] = "<5B"
    sus_s3: int = 0
    sus_s4: int = 0
    sus_s5: int = 0
    thrm: int = 0
    thrmtrip: int = 0

@dataclass(frozen=True)
class ResetLpc(Flag):
    """value 1: enter the USB bootloader."""
    ID: ClassVar[int] = 59

@dataclass(frozen=True)
class PowerOff(Request):
    ID: ClassVar[int] = 60

@dataclass(frozen=True)
class PowerSourceReadings(Struct):
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
class SetNrst(Flag):
    ID: ClassVar[int] = 73

@dataclass(frozen=True)
class GetNrst(Request):
    ID: ClassVar[int] = 74

@dataclass(frozen=True)
class Nrst(Flag):
    ID: ClassVar[int] = 75

@dataclass(frozen=True)
class SetBoot(Flag):
    ID: ClassVar[int] = 76

@dataclass(frozen=True)
class GetBoot(Request):
    ID: ClassVar[int] = 77

@dataclass(frozen=True)
class Boot(Flag):
    ID: ClassVar[int] = 78

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
        return pack("<BIffffB", self.charger, self.time, self.voltage, self.current,
                     self.temp1, self.temp2, self.state) + ascii_bytes(self.state_text)

    @classmethod
    def from_data(cls, data: bytes):
        head, rest = unpack_head("<BIffffB", data)
        return cls(*head, latin1(rest))

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
class ChargerVersion(Struct):
    ID: ClassVar[int] = 82
    FMT: ClassVar[str] = "<BBBB"
    charger: int = 0
    major: int = 0
    minor: int = 0
    patch: int = 0

@dataclass(frozen=True)
class ChargerGetVersion(Struct):
    ID: ClassVar[int] = 83
    FMT: ClassVar[str] = "<B"
    charger: int = 0

@dataclass(frozen=True)
class ChargerClearError(Struct):
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
        return pack("<BI", self.charger, self.time) + ascii_bytes(self.text)

    @classmethod
    def from_data(cls, data: bytes):
        (charger, time), rest = unpack_head("<BI", data)
        return cls(charger, time, latin1(rest))

@dataclass(frozen=True)
class SetBatteryMin(Struct):
    """Minimum battery voltages (V) for lead-acid and NiMH packs."""
    ID: ClassVar[int] = 86
    FMT: ClassVar[str] = "<ff"
    pb_min: float = 19.0
    nimh_min: float = 19.8

@dataclass(frozen=True)
class GetBatteryMin(Request):
    ID: ClassVar[int] = 87

@dataclass(frozen=True)
class BatteryMin(Struct):
    ID: ClassVar[int] = 88
    FMT: ClassVar[str] = "<f"
    voltage: float = 0.0

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
        return pack("<IBB4H4B", self.time, self.accu_bits, self.flags, *self.voltages_mv,
                     *self.capacities) + ascii_bytes(self.text)

    @classmethod
    def from_data(cls, data: bytes):
        v, rest = unpack_head("<IBB4H4B", data)
        return cls(v[0], v[1], v[2], tuple(v[3:7]), tuple(v[7:11]), latin1(rest))

@dataclass(frozen=True)
class FestoolChargerHotswapStart(Request):
    ID: ClassVar[int] = 99

@dataclass(frozen=True)
class GetPowerButton(Request):
    ID: ClassVar[int] = 38

@dataclass(frozen=True)
class PowerButton(Flag):
    ID: ClassVar[int] = 39
