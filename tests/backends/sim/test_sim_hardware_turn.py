"""A robot turning through emulated hardware and stopped: the world's robot
turns as far as the host's odometry, integrated from the firmware's wheel
speeds, says it did.  The host ramps the body velocity (RampLimits) and the
firmware its motors; a world that ramped the wheels' speeds once more (its
own acceleration limits, slower than the host's deceleration of a turn)
turned on after the wheels had stopped: up to 0.8 rad more than the
odometry at 1.6 rad/s, and the robot's localisation paired every later scan
with a heading that was off by as much."""
import time

import pytest

from backends.sim.hardware import WorldHardware
from rll_bt.backend import Pose2D, SensorLost, open_backend, wrap_angle
from tests.backends.sim.test_sim_hardware import Running, fresh, late_motion


def turn_and_stop(running, backend, robot, omega, turned):
    """Turn at ``omega`` until the world's robot turned ``turned`` rad (a liveness bound of three minutes
    against a hang only), stop at once (as every skill's end does), let it settle.  The world's turn, the
    odometry's, and what a loaded machine could have hidden from the odometry (host cycles that came late)."""
    fresh(running, lambda: backend.drive(0.0, 0.0, 0.0))
    running.run(0.5)
    with running.lock:
        start, odo0 = robot.pose, backend.odometry().pose
    cycles0 = len(backend.base.cycle_periods())
    end = time.monotonic() + 180.0
    while time.monotonic() < end:
        with running.lock:
            if abs(wrap_angle(robot.pose.theta - start.theta)) >= turned:
                break
        try:
            backend.drive(0.0, 0.0, omega)
        except SensorLost:
            pass
        running.run(0.02)
    backend.stop()
    assert running.run(180.0, until=lambda: backend.odometry().omega == 0.0 and robot.velocity[2] == 0.0)
    running.run(0.3)
    with running.lock:
        world = wrap_angle(robot.pose.theta - start.theta)
        odo = wrap_angle(backend.odometry().pose.theta - odo0.theta)
    periods = backend.base.cycle_periods()
    return world, odo, late_motion(periods[min(cycles0, len(periods)):], abs(omega))


@pytest.mark.parametrize("devices", ["threads", "process"])
def test_a_turn_stopped_at_full_speed_ends_where_the_odometry_says(make_world, devices):
    world = make_world("rcll2016", seed=3)
    world.add_robot("CYAN", 1, pose=Pose2D(3.0, 2.0, 0.3), laser_noise=0.0)
    hw = WorldHardware(world, laser="urg", camera_fps=1.0, devices=devices)
    rig = hw.add(("CYAN", 1))
    running = Running(world, hw)
    backend = open_backend("robotino", robot_config=rig.config())
    robot = world.robots[("CYAN", 1)]
    try:
        world_turn, odo_turn, hidden = turn_and_stop(running, backend, robot, 1.5, 1.2)
        assert world_turn > 1.2, (world_turn, odo_turn)
        # the odometry counted the world's turn (its own noise aside: the world's robot has none here)
        assert odo_turn == pytest.approx(world_turn, abs=0.05 + hidden), (world_turn, odo_turn, hidden)
    finally:
        backend.close()
        running.stop()
        hw.stop()
