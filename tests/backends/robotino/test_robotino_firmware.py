"""The emulator's base firmware model, driven directly (no pty)."""
import pytest

from backends.robotino import tags as T
from backends.robotino.firmware import BaseFirmware
from backends.robotino.framing import Frame, FrameDecoder, encode_frame


def frame_of(*tags):
    return encode_frame(T.encode_tags(tags))


def reply_tags(fw):
    raw = fw.take_reply()
    if raw is None:
        return None
    (event,) = FrameDecoder(4096).feed(raw)
    assert isinstance(event, Frame)
    return T.decode_tags(event.payload)


def test_reply_carries_power_readings_and_power_button_last():
    fw = BaseFirmware()
    fw.receive(frame_of(T.GetHwVersion(), T.GetSwVersion(), T.GetBumper()), 0.001)
    tags = reply_tags(fw)
    assert tags[:3] == [T.HwVersion("3.0.0"), T.SwVersion("1.2.3"), T.Bumper(0)]
    assert isinstance(tags[3], T.PowerSourceReadings) and tags[3].voltage == pytest.approx(24.5)
    assert tags[4] == T.PowerButton(0) and len(tags) == 5
    assert reply_tags(fw) is None                      # nothing new, nothing sent


def test_set_only_frame_gets_no_reply():
    fw = BaseFirmware()
    fw.receive(frame_of(T.SetMotorSpeed(0, 100), T.SetAllDigitalOutputs(0), T.SetEmergencyBumper(1)), 0.001)
    assert reply_tags(fw) is None
    assert fw.motors[0].setpoint == 100 and fw.emergency_bumper


def test_error_texts_as_the_firmware_prints_them():
    fw = BaseFirmware()
    # GET_BUMPER: payload 24 00, sum = 2 + 0x24 = 0x26, checksum 0xFFDA -> DA FF on the wire;
    # flipping DA to 25 makes the base receive 0xFF25 where it computes 0xFFDA
    bad = bytearray(frame_of(T.GetBumper()))
    assert bad == bytearray.fromhex("AA 0200 2400 DAFF")
    bad[-2] ^= 0xFF
    fw.receive(bytes(bad), 0.001)
    assert reply_tags(fw)[0] == T.Error("RX checksum mismatch ff25 ffda")
    fw.receive(frame_of(T.RawTag(200, b"")), 0.002)
    assert reply_tags(fw)[0] == T.Error("Tag 200 not implemented")
    fw.receive(encode_frame(bytes([9, 2, 0, 1])), 0.003)
    assert reply_tags(fw)[0] == T.Error("TAG_SET_MOTOR_SPEED invalid length 2")
    fw.receive(frame_of(T.SetMotorSpeed(4, 1)), 0.004)
    assert reply_tags(fw)[0] == T.Error("TAG_SET_MOTOR_SPEED invalid motor 4")
    fw.receive(encode_frame(bytes([36, 0, 6, 5])), 0.005)
    assert reply_tags(fw)[:2] == [T.Bumper(0), T.Error("tag_length=5 greater than length=2")]
    fw.receive(bytes.fromhex("AA 0102"), 0.006)
    assert reply_tags(fw)[0] == T.Error("payload to long: 513 > 512\n\r")
    fw.receive(frame_of(T.SetMotorAccelLimits(0, 100.0, 200.0)), 0.007)
    assert reply_tags(fw)[0].text.startswith("TAG_SET_MOTOR_ACCEL_LIMITS invalid min 100.000000")


def test_watchdog_stops_motors_300_to_400_ms_after_the_last_frame():
    fw = BaseFirmware()
    fw.receive(frame_of(T.SetMotorSpeed(0, 1200), T.SetMotorSpeed(1, -600)), 0.150)
    fw.advance(0.449)                       # ticks at 200, 300, 400: three without frames
    assert fw.motors[0].setpoint == 1200 and fw.motors[0].ss == pytest.approx(1200)
    fw.advance(0.501)                       # the 4th tick (500 ms) stops everything
    assert [m.setpoint for m in fw.motors] == [0, 0, 0, 0] and fw.motors[0].ss == 0
    assert fw.watchdog_trips == 1 and fw.watchdog_motion_stops == 1
    # a GET poll revives the link but does not restart the motors
    fw.receive(frame_of(T.GetAllMotorReadings()), 0.6)
    fw.advance(0.9)
    assert fw.motors[0].setpoint == 0
    fw.receive(frame_of(T.SetMotorSpeed(0, 300)), 0.95)
    fw.advance(1.0)
    assert fw.motors[0].ss == pytest.approx(300)


def test_polls_keep_the_watchdog_quiet():
    fw = BaseFirmware()
    fw.receive(frame_of(T.SetMotorSpeed(2, 900)), 0.001)
    for i in range(1, 400):                     # 2 s of 5 ms polls
        fw.receive(frame_of(T.GetAllMotorReadings()), 0.001 + i * 0.005)
        fw.take_reply()
    assert fw.watchdog_trips == 0 and fw.motors[2].setpoint == 900


def poll_until(fw, t_end, t=None, period=0.05):
    """Keep the watchdog fed with GET polls up to t_end."""
    t = fw.now if t is None else t
    while t < t_end:
        t = min(t + period, t_end)
        fw.receive(frame_of(T.GetBumper()), t)
        fw.take_reply()


def test_motor_accel_limit_resolution_and_ticks():
    fw = BaseFirmware()
    fw.receive(frame_of(T.SetMotorSpeed(0, 1200)), 0.0)
    fw.advance(0.050)                            # 12 rpm/ms: 600 rpm after 50 ms
    assert fw.motors[0].ss == pytest.approx(600)
    poll_until(fw, 0.2)
    readings = fw.motor_readings()
    assert readings.speeds[0] == 1200            # 40 ticks/ms exactly
    fw.receive(frame_of(T.SetMotorAccelLimits(1, -2000.0, 2000.0), T.SetMotorSpeed(1, 100)), 0.2)
    fw.advance(0.203)
    assert fw.motors[1].ss == pytest.approx(6.0)
    poll_until(fw, 1.2)
    assert fw.motor_readings().speeds[1] in (90, 120)    # 3.33 ticks/ms, 30 rpm steps
    # 2000 ticks per revolution, rpm / 30 ticks per ms: the 1 ms ramp steps 12, 24, .. 1200 rpm
    # give sum(12 k, k=1..100) / 30 = 2020 ticks, then 1100 ms at 40 ticks/ms
    assert fw.motor_readings().positions[0] == 2020 + 1100 * 40
    fw.receive(frame_of(T.GetMotorAccelLimits(1)), 1.2)
    assert reply_tags(fw)[0] == T.MotorAccelLimits(1, -2000.0, 2000.0)


def test_ground_truth_follows_the_wheels():
    fw = BaseFirmware()
    sp = fw.kinematics.setpoints(0.2, 0.0, 0.0)
    fw.receive(frame_of(*(T.SetMotorSpeed(i, sp[i]) for i in range(3))), 0.0)
    for i in range(1, 100):
        fw.receive(frame_of(T.GetOdometry()), i * 0.01)
        fw.take_reply()
    x, y, th = fw.pose
    assert x == pytest.approx(0.2 * 0.99 - 0.2 * 0.5 * 0.2 / 0.2 * 0.07, abs=0.01)
    assert abs(y) < 1e-3 and abs(th) < 1e-3


def test_emergency_bumper_stops_motors():
    fw = BaseFirmware()
    fw.receive(frame_of(T.SetEmergencyBumper(1), T.SetMotorSpeed(0, 500)), 0.0)
    fw.advance(0.05)
    fw.bumper = True
    fw.receive(frame_of(T.GetBumper()), 0.06)
    fw.advance(0.07)
    assert fw.motors[0].setpoint == 0 and fw.motors[0].ss == 0


def test_fw2_ignores_the_gyro_requests():
    fw = BaseFirmware(sw_version="2.1.0")
    for tag in (T.GetGyroZAngle(), T.GyroGetParam(), T.GyroSetParam(0, 0.5)):
        fw.receive(frame_of(tag), 0.0)
        assert reply_tags(fw) is None                  # the gyro was removed in 2.0.0
    assert fw.gyro_param[0] != 0.5
    fw1 = BaseFirmware()
    fw1.receive(frame_of(T.GetGyroZAngle()), 0.0)
    assert isinstance(reply_tags(fw1)[0], T.GyroZAngle)
    fw1.receive(frame_of(T.GyroSetParam(0, 0.5), T.GyroGetParam()), 0.0)
    assert reply_tags(fw1)[0] == T.GyroParam(0.5, fw1.gyro_param[1])


def test_charger_info_and_version_on_demand():
    fw = BaseFirmware(charger_info_period=0.5)
    fw.receive(frame_of(T.ChargerGetVersion(1)), 0.6)
    assert reply_tags(fw) is None          # the charger answers over CAN, later
    fw.receive(frame_of(T.GetBumper()), 0.61)
    tags = reply_tags(fw)
    names = [type(t).__name__ for t in tags]
    assert names == ["Bumper", "ChargerInfo", "ChargerInfo", "ChargerVersion", "PowerSourceReadings",
                     "PowerButton"]
    assert tags[3] == T.ChargerVersion(1, 1, 2, 3)


def test_frames_that_waited_for_a_late_emulator_thread_do_not_trip_the_watchdog():
    """The emulator's thread read the pty 600 ms late: the host's polls of that
    time (every 5 ms) were waiting there together.  A microcontroller took each
    as it came, so they must not count as a host gone quiet; a host that was
    quiet and sent one frame at the end still trips the watchdog."""
    from backends.robotino.emulator import arrival_times

    def feed(fw, data, last, now):
        for when, chunk in arrival_times(data, last, now, 0.005):
            fw.receive(chunk, when)
        fw.advance(now)

    live = BaseFirmware()
    live.receive(frame_of(T.SetMotorSpeed(0, 1200)), 0.1)
    polls = b"".join(frame_of(T.SetMotorSpeed(0, 1200), T.GetAllMotorReadings()) for _ in range(120))
    feed(live, polls[:7] , 0.1, 0.1)                       # a frame split across reads is whole again
    feed(live, polls[7:], 0.1, 0.7)
    assert live.watchdog_trips == 0 and live.motors[0].setpoint == 1200
    assert live.rx_counter == 121

    quiet = BaseFirmware()
    quiet.receive(frame_of(T.SetMotorSpeed(0, 1200)), 0.1)
    feed(quiet, frame_of(T.SetMotorSpeed(0, 1200)), 0.1, 0.7)
    assert quiet.watchdog_trips == 1 and quiet.watchdog_motion_stops == 1
