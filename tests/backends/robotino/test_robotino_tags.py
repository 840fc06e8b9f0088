"""Every tag of the firmware table encodes and decodes as a typed value."""
import struct

import pytest

from backends.robotino import tags as T

# one exactly representable value per tag (floats chosen to survive float32)
SAMPLES = [
    T.GetHwVersion(), T.HwVersion("3.0.0"), T.GetSwVersion(), T.SwVersion("2.1.0"),
    T.GetDistanceSensorReadings(), T.DistanceSensorReadings(tuple(0.25 * i for i in range(9))),
    T.GetAdcParameters(), T.AdcParameters(12, 2.5),
    T.SetMotorSpeed(3, -3000), T.GetAllMotorSpeeds(), T.AllMotorSpeeds((30, -60, 0, 32767)),
    T.SetMotorPosition(1, -123456), T.GetAllMotorPositions(), T.AllMotorPositions((1, -2, 2**31 - 1, -2**31)),
    T.SetMotorPidParameters(2, 0.5, 0.25, 0.0), T.GetAllMotorPidParameters(),
    T.AllMotorPidParameters(((0.5, 0.125, 0.0),) * 4),
    T.SetAllDigitalOutputs(0b10100101), T.SetAllRelays(3), T.SetOdometry(1.5, -2.25, 0.5),
    T.SetOdometryRotation(-1.0), T.GetOdometry(), T.Odometry(0.5, 0.25, -3.0),
    T.GetAllMotorCurrentReadings(), T.AllMotorCurrentReadings((0.5, 1.0, 1.5, 2.0)),
    T.GetAllAnalogInputs(), T.AllAnalogInputs(tuple(float(i) for i in range(8))),
    T.GetAllDigitalInputs(), T.AllDigitalInputs(0x81), T.GetBumper(), T.Bumper(1),
    T.GetPowerButton(), T.PowerButton(1), T.SetFpgaPower(1), T.GetFpgaPower(), T.FpgaPower(0),
    T.GetPwrOkState(), T.PwrOkState(1), T.SetPwrOkState(0), T.SetPwm(6, 200), T.SetMotorOn(3, 0),
    T.SetPwrbtn(1), T.SetSysReset(0), T.GetComExpressStates(), T.ComExpressStates(1, 1, 0, 1, 0),
    T.GetAllMotorReadings(), T.AllMotorReadings((30, -30, 0, 0), (100, -200, 0, 5), (0.5, 0.25, 0.0, 1.0)),
    T.GetIpAddress(), T.IpAddress(0x7F000001, 0xFFFF0000), T.SetIpAddress(0xC0A80001, 0xFFFFFF00),
    T.SetEmergencyBumper(1), T.SetMotorMode(1, 2), T.ResetLpc(1), T.PowerOff(),
    T.SetSafteyVelocity(400.0), T.GetSafteyVelocity(), T.SafteyVelocity(350.0),
    T.PowerSourceReadings(24.5, 1.25, 1, 2, 1, 0, 60000),
    T.SetMotorAccelLimits(0, -11500.0, 11500.0), T.MotorAccelLimits(1, -12000.0, 12000.0),
    T.GetMotorAccelLimits(2), T.GetGyroZAngle(), T.GyroZAngle(0.5, -0.25),
    T.GetCanMsg(), T.CanMsg(0x123, 3, b"\x01\x02\x03\x00\x00\x00\x00\x00"),
    T.SetNrst(1), T.GetNrst(), T.Nrst(0), T.SetBoot(2), T.GetBoot(), T.Boot(1), T.ConfigReset(1),
    T.ChargerInfo(1, 3600, 24.5, -1.5, 25.0, 26.5, 2, "Charging"), T.ChargerEvent(b"\x01"),
    T.ChargerVersion(0, 1, 2, 3), T.ChargerGetVersion(1), T.ChargerClearError(2),
    T.ChargerError(0, 77, "over temperature"),
    T.SetBatteryMin(19.0, 19.75), T.GetBatteryMin(), T.BatteryMin(19.75),
    T.GetGyroData(), T.GyroData(((1000, 0.5), (1001, -0.25))),
    T.GetGpain(10), T.Gpain(3, 4.5), T.GetVersionBits(), T.VersionBits(1, 0),
    T.GyroSetParam(1, 1.5), T.GyroGetParam(), T.GyroParam(0.25, 1.0),
    T.FestoolChargerInfo(99, 0x31, 0x03, (24000, 23900, 0, 0), (95, 90, 0, 0), "ok"),
    T.FestoolChargerHotswapStart(), T.MotorDebug(1, 5000, 10, ((100, 90, 500, 20), (100, 120, 510, 18))),
    T.SetMotorDebug(2), T.Info("hello"), T.Warning("careful"), T.Error("Tag 200 not implemented"),
]


def test_every_tag_of_the_table_has_a_sample():
    assert {type(s).ID for s in SAMPLES} == set(T.TAGS)
    # the table's gaps stay gaps: 24, 25, 28-31 and 64 are undefined
    assert not {24, 25, 28, 29, 30, 31, 64} & set(T.TAGS)


@pytest.mark.parametrize("tag", SAMPLES, ids=lambda t: type(t).__name__)
def test_tag_round_trips(tag):
    wire = tag.encode()
    assert wire[0] == tag.ID and wire[1] == len(wire) - 2
    assert T.decode_tags(wire) == [tag]


def test_layouts_and_lengths_from_the_table():
    assert T.SetMotorSpeed(1, -2).encode() == bytes([9, 3, 1]) + struct.pack("<h", -2)
    assert len(T.AllMotorReadings().encode()) == 2 + 40
    assert len(T.PowerSourceReadings().encode()) == 2 + 16
    assert len(T.DistanceSensorReadings((0.0,) * 9).encode()) == 2 + 36
    assert len(T.AllMotorPidParameters().encode()) == 2 + 48
    assert len(T.SetMotorAccelLimits().encode()) == 2 + 9
    assert len(T.ChargerInfo(state_text="abc").encode()) == 2 + 22 + 3
    assert len(T.ChargerError(text="abcd").encode()) == 2 + 5 + 4
    assert T.HwVersion("3.0.0").encode() == b"\x02\x053.0.0"
    assert T.tag_name(66) == "SET_MOTOR_ACCEL_LIMITS" and T.tag_name(61) == "SET_SAFTEY_VELOCITY"


def test_unknown_tag_is_a_raw_tag():
    tags = T.decode_tags(bytes([200, 2, 1, 2, 36, 0]))
    assert tags == [T.RawTag(200, b"\x01\x02", "unknown tag id"), T.GetBumper()]


def test_wrong_length_is_a_raw_tag_with_a_reason():
    (tag,) = T.decode_tags(bytes([9, 2, 0, 5]))
    assert isinstance(tag, T.RawTag) and tag.tag_id == 9 and "SetMotorSpeed" in tag.reason


def test_tag_running_past_the_payload_is_marked_truncated():
    tags = T.decode_tags(bytes([37, 1, 1, 6, 36, 0, 0]))
    assert tags[0] == T.Bumper(1)
    assert tags[1].truncated and tags[1].tag_id == 6


def test_values_outside_the_layout_are_refused():
    with pytest.raises(T.TagError):
        T.SetMotorSpeed(0, 40000).encode()
    with pytest.raises(T.TagError):
        T.SetMotorSpeed(4096, 0).encode()
    with pytest.raises(T.TagError):
        T.Error("x" * 300).encode()
