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
    """Command ``v`` for about ``seconds`` (a loaded machine may stretch it; nothing asserts how long)."""
    end = time.monotonic() + seconds
    while time.monotonic() < end:
        backend.drive(*v)
        time.sleep(period)


def drive_until(backend, v, until, liveness=120.0, period=0.05):
    """Command ``v`` until ``until()`` holds (``liveness`` bounds a hang only); whether it held."""
    end = time.monotonic() + liveness
    while time.monotonic() < end:
        backend.drive(*v)
        if until():
            return True
        time.sleep(period)
    return until()


def settle(emu, robot, liveness=120.0):
    """Stop, and wait until the wheels stand and the host has polled them standing."""
    robot.stop()
    end = time.monotonic() + liveness
    while time.monotonic() < end:
        odo = robot.odometry()
        if not any(emu.wheel_speeds()[:3]) and odo.vx == odo.vy == odo.omega == 0.0:
            return True
        time.sleep(0.02)
    return False


def late_motion(periods, speed):
    """How far a robot at ``speed`` can go unseen by the host's odometry in cycles longer than the 20 ms an
    idle machine takes (the host integrates the speeds it reads, Fawkes' way): 0 when every cycle was on time."""
    return speed * sum(max(0.0, p - 0.02) for p in periods)


def trips_follow_silences(emu):
    """Every watchdog trip of the base came after a silence of the host of at least the watchdog's
    three 100 ms ticks (the frames as the base received them): the base never stops a host that polls."""
    with emu.lock:
        heard = [t for t, _ in emu.firmware.rx_log]
        trips = list(emu.firmware.watchdog_trip_times)
    for trip in trips:
        before = [t for t in heard if t <= trip]
        assert not before or trip - before[-1] >= 0.3 - 1e-9, (trip, before[-3:])


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
    sp = expected_setpoints(*v)
    reached = []

    def done():
        odo = robot.odometry()
        if odo.vx == pytest.approx(0.2, abs=0.02) and odo.omega == pytest.approx(0.4, abs=0.05):
            reached.append(odo)
        with emu.lock:
            polls = len(emu.firmware.rx_log)
        return reached and polls > 30 and emu.ground_truth()[0] > 0.2 and emu.setpoints()[:3] == sp
    assert drive_until(robot, v, done)
    received = [rpm for _, motor, rpm in emu.received_setpoints() if motor == 0]
    nonzero = [r for r in received if r]
    # ramped, not a jump: the host's ramp (0.8 m/s^2, at most 0.1 s a cycle however late the cycle) needs at
    # least three cycles to 0.2 m/s, so the set-points pass through values below the final one
    assert abs(nonzero[0]) < abs(sp[0]) and len(set(nonzero)) >= 3
    # sent in every poll from the first on (the robot is still moving): however few polls a loaded machine ran
    with emu.lock:                                  # the emulator's thread appends to the log
        log = list(emu.firmware.rx_log)
    frames = [T.decode_tags(p) for _, p in log]
    first = next(i for i, tags in enumerate(frames) if any(isinstance(t, T.SetMotorSpeed) for t in tags))
    driving = frames[first:]
    assert len(driving) > 20
    assert all(sum(isinstance(t, T.SetMotorSpeed) for t in tags) == 3 for tags in driving)
    # the base stops only a host that went silent (on an idle machine: never; a loaded one can starve the
    # host's thread past the watchdog, which a real base must answer by stopping)
    trips_follow_silences(emu)
    # the host's odometry, integrated from the wheel speeds it polls, ends where the wheels took the robot,
    # up to what cycles a loaded machine made late could hide
    assert settle(emu, robot)
    odo, truth = robot.odometry(), emu.ground_truth()
    slack = late_motion(robot._base.cycle_periods(), math.hypot(0.2, 0.1) + RB * 0.4)
    assert odo.pose.x == pytest.approx(truth[0], abs=0.01 + slack)
    assert odo.pose.y == pytest.approx(truth[1], abs=0.01 + slack)
    assert odo.pose.theta == pytest.approx(truth[2], abs=0.02 + slack / RB)
    stats = robot.link_stats()
    assert stats.frames > 20 and stats.checksum_errors == 0 and stats.link_losses == 0


def test_deadman_stops_the_robot_when_commands_stop(emu, robot, wait_for):
    assert drive_until(robot, (0.3, 0.0, 0.0), lambda: emu.setpoints()[:3] == expected_setpoints(0.3, 0.0, 0.0))
    before_last = time.monotonic()                      # the last command is stamped after this
    robot.drive(0.3, 0.0, 0.0)
    assert wait_for(lambda: emu.setpoints()[:3] == (0, 0, 0) and not any(emu.wheel_speeds()[:3]), 1.5)
    # not before the deadman's 0.5 s (a loaded machine only makes it later; how much later is not asserted)
    assert time.monotonic() - before_last >= 0.5
    # ramped down by the host, not cut: the set-points after the last full one fall to zero step by step
    received = [rpm for _, motor, rpm in emu.received_setpoints() if motor == 0]
    full = max(i for i, rpm in enumerate(received) if rpm == expected_setpoints(0.3, 0.0, 0.0)[0])
    down = received[full:]
    assert down[-1] == 0 and all(abs(b) <= abs(a) for a, b in zip(down, down[1:])) and len(set(down)) >= 3
    assert robot.link_stats().deadman_stops == 1
    trips_follow_silences(emu)                          # the host stopped it (zero set-points), the watchdog no more


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
        v = (0.25, 0.0, 0.3)
        try:
            def hit():                  # the faults struck both ways, and the robot drives as commanded
                e, st = emu.stats(), robot.link_stats()
                return (e["corrupted"] > 0 and e["dropped"] > 0 and e["checksum_errors"] > 0
                        and st.checksum_errors + st.framing_errors > 0
                        and emu.setpoints()[:3] == expected_setpoints(*v))
            assert drive_until(robot, v, hit)
            assert settle(emu, robot)
            stats, truth, odo = robot.link_stats(), emu.ground_truth(), robot.odometry()
            slack = late_motion(robot._base.cycle_periods(), 0.25 + RB * 0.3)
        finally:
            robot.close()
    assert stats.link_losses == 0
    trips_follow_silences(emu)
    assert odo.pose.x == pytest.approx(truth[0], abs=0.03 + slack)
    assert odo.pose.theta == pytest.approx(truth[2], abs=0.05 + slack / RB)


def test_closed_port_is_reopened_and_driving_resumes(emu, wait_for):
    robot = RobotinoBackend(emu.device, reopen_interval=0.05)
    v = (0.2, 0.0, 0.0)
    try:
        assert drive_until(robot, v, lambda: emu.setpoints()[:3] == expected_setpoints(*v))
        emu.close_port(0.6)
        assert drive_until(robot, v, lambda: robot.link_stats().link_losses >= 1)
        assert drive_until(robot, v, lambda: robot.link_stats().reopens >= 1)
        assert drive_until(robot, v, lambda: emu.setpoints()[:3] == expected_setpoints(*v)
                           and any(emu.wheel_speeds()[:3]) and emu.watchdog_trips >= 1)
        # the base stopped while unplugged (its watchdog), and drives again on the reopened port
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
            assert drive_until(robot, (0.0, 0.2, 0.0),
                               lambda: robot.link_stats().reopens >= 2 and emu.stats()["connects"] >= 3)
            assert drive_until(robot, (0.0, 0.2, 0.0), lambda: emu.setpoints()[:3] == expected_setpoints(0.0, 0.2, 0.0))
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
    backend = RobotinoBackend(robot_config=dict(cfg, faults={"startup_wait": 120.0}))   # at once when it does
    try:
        assert backend.versions == ("3.0.0", "1.2.3")
    finally:
        backend.close()
