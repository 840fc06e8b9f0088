"""The real serial backend driving the firmware emulator through a pty."""
import math
import threading
import time
from types import SimpleNamespace

import pytest

from backends.robotino import tags as T
from backends.robotino.backend import RobotinoBackend
from backends.robotino.emulator import RobotinoEmulator
from backends.robotino.faults import Faults
from rll_bt.backend import BackendUnavailable, Capability, CapabilityError, open_backend

K = 60 * 32 / (2 * math.pi * 0.06)     # rpm per m/s at the rim (gear 32, rw 0.06)
RB = 0.175


def expected_setpoints(vx, vy, w):
    """Motor rpm from the fact sheet's forward kinematics, rounded half away from zero."""
    s3 = math.sqrt(3) / 2
    raw = (K * (-s3 * vx + 0.5 * vy + RB * w), K * (-vy + RB * w), K * (s3 * vx + 0.5 * vy + RB * w))
    return tuple(int(math.copysign(math.floor(abs(m) + 0.5), m)) for m in raw)


def drive_for(backend, seconds, v, period=0.05):
    end = time.monotonic() + seconds
    while time.monotonic() < end:
        backend.drive(*v)
        time.sleep(period)


@pytest.fixture
def emu():
    with RobotinoEmulator() as e:
        yield e


@pytest.fixture
def robot(emu):
    backend = RobotinoBackend(emu.device)
    yield backend
    backend.close()


def test_handshake_as_fawkes_does_it(emu, robot, wait_for):
    assert robot.versions == ("3.0.0", "1.2.3")
    assert wait_for(lambda: len(emu.firmware.rx_log) > 20, 1.0)
    payloads = [p for _, p in emu.firmware.rx_log]
    assert payloads[0] == T.encode_tags([T.GetHwVersion(), T.GetSwVersion()])
    assert payloads[1:4] == [T.SetAllDigitalOutputs(0).encode(), T.SetOdometry(0, 0, 0).encode(),
                             T.SetEmergencyBumper(1).encode()]
    poll = list(emu.firmware.rx_log)[-1][1]
    assert T.decode_tags(poll) == [T.GetAllMotorReadings(), T.GetDistanceSensorReadings(),
                                   T.GetAllAnalogInputs(), T.GetAllDigitalInputs(), T.GetBumper(),
                                   T.GetOdometry(), T.GetGyroZAngle()]


def test_velocity_gives_kinematic_setpoints_odometry_and_no_watchdog_stop(emu, robot):
    v = (0.2, -0.1, 0.4)
    drive_for(robot, 1.5, v)
    assert emu.setpoints()[:3] == expected_setpoints(*v)
    received = [rpm for _, motor, rpm in emu.received_setpoints() if motor == 0]
    nonzero = [r for r in received if r]
    # ramped, not a jump: the host's ramp (0.8 m/s^2, at most 0.1 s a cycle however late the cycle) needs at
    # least three cycles to 0.2 m/s, so the set-points pass through values below the final one
    assert abs(nonzero[0]) < abs(expected_setpoints(*v)[0]) and len(set(nonzero)) >= 3
    # sent in every poll from the first on (the robot is still moving): however few polls a loaded machine ran
    with emu.lock:                                  # the emulator's thread appends to the log
        log = list(emu.firmware.rx_log)
    frames = [T.decode_tags(p) for _, p in log]
    first = next(i for i, tags in enumerate(frames) if any(isinstance(t, T.SetMotorSpeed) for t in tags))
    driving = frames[first:]
    assert len(driving) > 20
    assert all(sum(isinstance(t, T.SetMotorSpeed) for t in tags) == 3 for tags in driving)
    assert emu.watchdog_trips == 0, (emu.stats(), max(robot._base.cycle_periods()), emu.firmware.watchdog_trip_times)
    odo, truth = robot.odometry(), emu.ground_truth()
    assert odo.pose.x == pytest.approx(truth[0], abs=0.01)
    assert odo.pose.y == pytest.approx(truth[1], abs=0.01)
    assert odo.pose.theta == pytest.approx(truth[2], abs=0.02)
    assert odo.vx == pytest.approx(0.2, abs=0.02) and odo.omega == pytest.approx(0.4, abs=0.05)
    assert truth[0] > 0.2
    stats = robot.link_stats()
    assert stats.frames > 20 and stats.checksum_errors == 0 and stats.link_losses == 0


def test_deadman_stops_the_robot_when_commands_stop(emu, robot, wait_for):
    drive_for(robot, 0.6, (0.3, 0.0, 0.0))
    last_command = time.monotonic()
    time.sleep(0.3)
    assert any(emu.wheel_speeds()[:3])                  # still moving before the deadman
    assert wait_for(lambda: not any(emu.wheel_speeds()[:3]), 1.5)
    stopped_after = time.monotonic() - last_command
    # deadman 0.5 s + host ramp (0.3 m/s at 1.5 m/s^2) + wheel ramp (12 rpm/ms) + polling
    assert 0.5 <= stopped_after < 0.5 + 0.2 + 0.13 + 0.45     # generous for loaded CI machines
    assert robot.link_stats().deadman_stops == 1
    assert emu.firmware.watchdog_motion_stops == 0      # the host stopped it, not the watchdog
    assert emu.setpoints()[:3] == (0, 0, 0)


def test_stop_is_immediate(emu, robot, wait_for):
    drive_for(robot, 0.5, (0.0, 0.0, 1.0))
    robot.stop()
    assert wait_for(lambda: emu.setpoints()[:3] == (0, 0, 0), 1.0)
    # zero set-points at once (no host ramp): the wheels stop within the base's 12 rpm/ms ramp
    assert wait_for(lambda: not any(emu.wheel_speeds()[:3]), 1.2)
    assert robot.link_stats().deadman_stops == 0


def test_corrupted_and_dropped_bytes_are_survived():
    with RobotinoEmulator(faults=Faults(corrupt=0.001, drop=0.001, seed=7)) as emu:
        robot = RobotinoBackend(emu.device, handshake_timeout=2.0)
        try:
            drive_for(robot, 2.0, (0.25, 0.0, 0.3))
            stats, truth, odo = robot.link_stats(), emu.ground_truth(), robot.odometry()
            assert emu.setpoints()[:3] == expected_setpoints(0.25, 0.0, 0.3)
        finally:
            robot.close()
        emu_stats = emu.stats()
    assert emu_stats["corrupted"] > 0 and emu_stats["dropped"] > 0
    assert stats.checksum_errors + stats.framing_errors > 0          # seen and counted
    assert emu_stats["checksum_errors"] > 0                           # the base saw bad frames too
    assert stats.link_losses == 0 and emu_stats["watchdog_motion_stops"] == 0
    assert odo.pose.x == pytest.approx(truth[0], abs=0.03)
    assert odo.pose.theta == pytest.approx(truth[2], abs=0.05)


def test_closed_port_is_reopened_and_driving_resumes(emu, wait_for):
    robot = RobotinoBackend(emu.device, reopen_interval=0.05)
    try:
        drive_for(robot, 0.4, (0.2, 0.0, 0.0))
        emu.close_port(0.6)
        drive_for(robot, 0.6, (0.2, 0.0, 0.0))
        assert robot.link_stats().link_losses >= 1
        assert wait_for(lambda: robot.link_stats().reopens >= 1, 1.0)
        drive_for(robot, 0.5, (0.2, 0.0, 0.0))
        assert emu.setpoints()[:3] == expected_setpoints(0.2, 0.0, 0.0)
        assert any(emu.wheel_speeds()[:3])
        assert emu.watchdog_trips >= 1                  # the base stopped while unplugged
    finally:
        robot.close()


def test_silent_base_triggers_the_nodata_timeout_and_reconnects(emu, wait_for):
    robot = RobotinoBackend(emu.device, nodata_timeout=0.4)
    try:
        emu.set_silent(True)
        assert wait_for(lambda: robot.link_stats().nodata_timeouts >= 1, 1.5)
        emu.set_silent(False)
        frames = robot.link_stats().frames
        assert wait_for(lambda: robot.link_stats().frames > frames + 10, 1.5)
    finally:
        robot.close()


def test_read_timeout_on_an_unfinished_frame(emu, robot, wait_for):
    emu.set_silent(True)
    time.sleep(0.05)
    emu.inject(bytes.fromhex("AA 2800 35"))             # a head and 1 of 40 payload bytes
    assert wait_for(lambda: robot.link_stats().read_timeouts >= 1, 2.0)
    emu.set_silent(False)
    frames = robot.link_stats().frames
    assert wait_for(lambda: robot.link_stats().frames > frames + 5, 1.0)


def test_backend_interface_and_sensors(emu, wait_for):
    robot = open_backend("robotino", device=emu.device)
    with robot:
        assert robot.capabilities == (Capability.DRIVE | Capability.ODOMETRY | Capability.BUMPER
                                      | Capability.BATTERY)
        with pytest.raises(CapabilityError):
            robot.laser_scan()
        with pytest.raises(CapabilityError):
            robot.camera_image()
        with pytest.raises(CapabilityError):
            robot.gripper_open()
        assert robot.holding() is None
        assert wait_for(lambda: robot.readings().power is not None, 2.0)
        battery = robot.battery()
        assert battery.voltage == pytest.approx(24.5) and battery.soc == pytest.approx(1.0)
        assert robot.bumper() is False
        with emu.lock:
            emu.firmware.bumper = True
            emu.firmware.distance[3] = 2.5
            emu.firmware.digital_inputs = 0b100
        assert wait_for(robot.bumper, 2.0)
        assert robot.readings().distance_voltages[3] == pytest.approx(2.5)
        assert robot.readings().digital_inputs == 0b100


def test_unreachable_devices_raise_backend_unavailable(tmp_path):
    with pytest.raises(BackendUnavailable, match="cannot open"):
        RobotinoBackend(str(tmp_path / "ttyACM9"))
    with RobotinoEmulator() as emu:
        emu.set_silent(True)
        with pytest.raises(BackendUnavailable, match="version inquiry"):
            RobotinoBackend(emu.device, handshake_timeout=0.3)


def test_device_found_by_usb_id(monkeypatch, emu):
    from backends.robotino import serial_port
    ports = [SimpleNamespace(device="/dev/ttyS0", vid=None, pid=None),
             SimpleNamespace(device=emu.device, vid=0x1E29, pid=0x040D)]
    monkeypatch.setattr(serial_port.list_ports, "comports", lambda: ports)
    robot = RobotinoBackend()
    try:
        assert robot.base.device == emu.device and robot.versions[0] == "3.0.0"
    finally:
        robot.close()
    monkeypatch.setattr(serial_port.list_ports, "comports", lambda: ports[:1])
    with pytest.raises(BackendUnavailable, match="1E29:040D"):
        RobotinoBackend()


def test_periodic_unplugging_and_delayed_replies(wait_for):
    faults = Faults(delay_ms=30, close_every=0.4, closed_for=0.1, seed=2)
    with RobotinoEmulator(faults=faults) as emu:
        t0 = time.monotonic()
        robot = RobotinoBackend(emu.device, handshake_timeout=2.0, reopen_interval=0.05)
        try:
            assert time.monotonic() - t0 >= 0.03            # the version reply came 30 ms late
            drive_for(robot, 2.0, (0.0, 0.2, 0.0))
            assert robot.link_stats().reopens >= 2 and emu.stats()["connects"] >= 3
            assert wait_for(lambda: emu.setpoints()[:3] == expected_setpoints(0.0, 0.2, 0.0), 1.0)
        finally:
            robot.close()


def test_write_error_closes_and_reopens_the_port(emu, robot, wait_for, monkeypatch):
    import serial

    from backends.robotino import base as base_module
    broken, write_all = robot.base._port, base_module.write_all

    def broken_write(port, data, *args, **kw):         # the port open now fails; a reopened one works
        if port is broken:
            raise serial.SerialException("write failed: [Errno 5] Input/output error")
        return write_all(port, data, *args, **kw)

    monkeypatch.setattr(base_module, "write_all", broken_write)
    assert wait_for(lambda: robot.link_stats().reopens >= 1, 1.0)
    stats = robot.link_stats()
    assert stats.write_errors == 1 and stats.link_losses == 1
    frames = stats.frames
    assert wait_for(lambda: robot.link_stats().frames > frames + 5, 1.0)


def test_startup_wait_of_the_robot_config_is_how_long_the_base_may_take_to_answer(emu):
    cfg = {"name": "r", "base": {"type": "robotino3", "device": emu.device}}
    emu.set_silent(True)                                # a base that does not answer (yet)
    with pytest.raises(BackendUnavailable, match="within 1 s"):
        RobotinoBackend(robot_config=cfg)               # the handshake's own 1 s
    threading.Timer(3.0, emu.set_silent, (False,)).start()        # ... answers after 3 s
    backend = RobotinoBackend(robot_config=dict(cfg, faults={"startup_wait": 20.0}))
    try:
        assert backend.versions == ("3.0.0", "1.2.3")
    finally:
        backend.close()
