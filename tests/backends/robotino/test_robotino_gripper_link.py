"""The gripper driver against the emulated Arduino sketch, through a pty."""
import time

import pytest

from backends.robotino import gripper_protocol as P
from backends.robotino.arduino import GripperFirmware
from backends.robotino.backend import RobotinoBackend
from backends.robotino.emulator import RobotinoEmulator
from backends.robotino.gripper import GripperConfig
from backends.robotino.holding import HoldingSensor
from rll_bt.backend import BackendError, Capability, GripperState

FAST = GripperConfig(status_period=0.2, reopen_interval=0.2)


@pytest.fixture
def emu():
    with RobotinoEmulator(gripper=True, gripper_firmware=GripperFirmware(speed=20000.0,
                                                                         home_time=0.1)) as e:
        yield e


@pytest.fixture
def robot(emu, wait_for):
    """A backend with the gripper (fast status requests), homed and idle."""
    backend = RobotinoBackend(emu.device, gripper_device=emu.gripper_device, gripper_config=FAST)
    assert wait_for(lambda: idle(backend), 2.0)
    yield backend
    backend.close()


def idle(robot):
    return robot.gripper_status().state == GripperState.IDLE


def test_hello_gets_config_and_homing_and_status_every_second(emu, wait_for):
    opened = time.monotonic()
    robot = RobotinoBackend(emu.device, gripper_device=emu.gripper_device)
    try:
        assert Capability.GRIPPER in robot.capabilities
        assert wait_for(lambda: idle(robot), 2.0)
        # the sketch's boot status can make the gripper idle before the configuration
        # written in answer to HELLO has reached it: wait for the commands themselves
        assert wait_for(lambda: len(emu.gripper.commands_seen) >= 10, 3.0)
        seen = emu.gripper.commands_seen
        assert seen[:10] == [("m", 7000), ("n", 7000), ("o", 7000), ("p", 15000), ("x", 4000),
                             ("y", 4000), ("z", 4000), ("a", 7000), ("T", 240), ("C", 0)]
        assert ("S", 0) not in seen
        assert wait_for(lambda: ("S", 0) in emu.gripper.commands_seen, 3.0)
        assert time.monotonic() - opened >= 0.9         # the first request after one period
        assert robot.gripper.stats.hellos == 1
    finally:
        robot.close()


def moving_until_confirmed(emu, robot, command, *args):
    """Send ``command``: the gripper reads MOVING until the sketch confirmed it, which takes a status
    request (a loaded machine may have sent one before the test looks: then either state will do)."""
    asked = emu.gripper.commands_seen.count(("S", 0))
    command(*args)
    state = robot.gripper_status().state
    assert state == GripperState.MOVING or emu.gripper.commands_seen.count(("S", 0)) > asked, state


def test_open_close_move_and_status(emu, robot, wait_for):
    moving_until_confirmed(emu, robot, robot.gripper_open)
    assert wait_for(lambda: idle(robot) and robot.gripper_status().is_open, 2.0)
    moving_until_confirmed(emu, robot, robot.gripper_move, 0.02, 0.01, 0.005)
    assert wait_for(lambda: idle(robot), 2.0)
    status = robot.gripper_status()
    assert status.position == pytest.approx((0.02, 0.01, 0.005), abs=2e-4)
    assert emu.gripper.target == [float(v) for v in P.StepsPerMetre().to_steps(0.02, 0.01, 0.005)]
    robot.gripper_close()
    assert wait_for(lambda: idle(robot) and not robot.gripper_status().is_open, 2.0)
    assert status.holding is None
    with pytest.raises(BackendError):
        robot.gripper_move(-0.01, 0.0, 0.0)


def test_lines_with_bad_checksums_are_dropped(emu, robot, wait_for):
    before = robot.gripper_status()
    emu.inject(b"AT I 999 999 999 0 OPEN+12\r\n", which="gripper")
    assert wait_for(lambda: robot.gripper.stats.rejected >= 1, 2.0)
    assert robot.gripper_status().position == before.position
    assert robot.gripper_status().is_open == before.is_open


def test_error_status_closes_and_reopens_with_hello(emu, robot, wait_for):
    emu.fail_gripper("end stop Z")
    assert wait_for(lambda: robot.gripper_status().state == GripperState.ERROR, 2.0)
    assert robot.gripper_status().message == "end stop Z"
    assert wait_for(lambda: robot.gripper.stats.hellos == 2, 3.0)      # reopened, reset
    assert wait_for(lambda: idle(robot), 2.0)
    assert robot.gripper.stats.reopens >= 1 and emu.stats()["gripper_connects"] == 2


def test_holding_from_a_configured_sensor(emu, wait_for):
    robot = RobotinoBackend(emu.device, gripper_device=emu.gripper_device, gripper_config=FAST,
                            holding_sensor="distance:2>1.0")
    try:
        with emu.lock:
            emu.firmware.distance[2] = 2.0
        assert wait_for(lambda: robot.holding() is True, 2.0)
        assert robot.gripper_status().holding is True
        with emu.lock:
            emu.firmware.distance[2] = 0.3
        assert wait_for(lambda: robot.holding() is False, 2.0)
    finally:
        robot.close()


def test_holding_sensor_specs():
    assert HoldingSensor.parse("analog:0<2.5") == HoldingSensor("analog", 0, 2.5, False)
    assert HoldingSensor.parse("digital:3=0") == HoldingSensor("digital", 3, 0.0, False)
    assert HoldingSensor.parse("digital:7") == HoldingSensor("digital", 7, 0.0, True)
    for bad in ("distance:9>1", "analog:1", "camera:0>1", "digital:2=5"):
        with pytest.raises(ValueError):
            HoldingSensor.parse(bad)
