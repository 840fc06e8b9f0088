"""A robot's devices' process that stops running (SIGSTOP here; a loaded
machine does the same for seconds): the world, the emulated base firmware
and the host's odometry stay one story, and the host's base link goes on
when the process runs again."""
import os
import signal
import time

import pytest

from backends.sim.hardware import WorldHardware
from backends.sim.hardware_parts import SILENT_STOP
from rll_bt.backend import Pose2D, SensorLost, open_backend
from tests.backends.sim.test_sim_hardware import Running, fresh, late_motion


def drive_for(running, backend, seconds, vx=0.2, until=None):
    """Command ``vx`` for ``seconds`` or until ``until()`` (a lost sensor stops the robot: the command is
    then left); whether ``until()`` held."""
    end = time.monotonic() + seconds
    while time.monotonic() < end:
        if until is not None and until():
            return True
        try:
            backend.drive(vx, 0.0, 0.0)
        except SensorLost:
            pass
        running.run(0.05)
    return until is None or until()


def stalled_episode(running, rig, backend, robot):
    """Drive, SIGSTOP the devices' process for 2.9 s while the host keeps commanding, SIGCONT, stop.
    The world's motion during the silence and over the episode, the host's odometry over it, and the
    longest time the world was not stepped (a loaded machine: the world drops what it cannot catch up)."""
    fresh(running, lambda: backend.drive(0.0, 0.0, 0.0))
    with running.lock:
        start, odo0 = robot.pose, backend.odometry().pose
    assert drive_for(running, backend, 180.0, until=lambda: robot.pose.relative_to(start).x > 0.1)   # liveness
    running.longest_gap, dropped0, cycles0 = 0.0, running.dropped, len(backend.base.cycle_periods())
    os.kill(rig.pid, signal.SIGSTOP)
    try:
        drive_for(running, backend, SILENT_STOP + 0.4)                  # the host keeps commanding
        with running.lock:
            stalled = robot.pose
        drive_for(running, backend, 2.2)                                # past the host's no-data timeout (2 s)
        with running.lock:
            during = robot.pose.relative_to(stalled)
    finally:
        os.kill(rig.pid, signal.SIGCONT)
    backend.stop()
    running.run(1.0)
    fresh(running, lambda: backend.drive(0.0, 0.0, 0.0))
    running.run(0.5)
    with running.lock:
        moved, odo = robot.pose.relative_to(start), backend.odometry().pose.relative_to(odo0)
    # what a loaded machine could hide from the odometry besides the stall: host cycles that came late, world
    # time dropped (tests/backends/sim/test_sim_hardware.py: 0 on an idle machine)
    periods = backend.base.cycle_periods()
    hidden = late_motion(periods[min(cycles0, len(periods)):], 0.2) + 0.2 * (running.dropped - dropped0)
    return during, moved, odo, hidden


def test_a_stalled_devices_process_stops_the_wheels_in_the_world_and_the_firmware_alike(make_world):
    world = make_world("rcll2016", seed=3)
    world.add_robot("CYAN", 1, pose=Pose2D(3.0, 2.0, 0.3), laser_noise=0.0)
    hw = WorldHardware(world, laser="urg", camera_fps=1.0, devices="process")
    rig = hw.add(("CYAN", 1))
    running = Running(world, hw)
    backend = open_backend("robotino", robot_config=rig.config())
    robot = world.robots[("CYAN", 1)]
    try:
        losses0 = backend.base.stats().link_losses
        during, moved, odo, hidden = stalled_episode(running, rig, backend, robot)
        # the world stopped the wheels when the base emulator fell silent, not seconds later
        assert abs(during.x) < 0.01 and abs(during.y) < 0.01, during
        # the firmware stopped its motors at the same moment, so the odometry the host integrated from
        # the speeds it polled counts no motion the world did not make, and misses little (the wheels
        # ran on for SILENT_STOP after the last poll the host got an answer to)
        assert odo.x <= moved.x + 0.02 + hidden, (odo, moved, hidden)
        assert odo.x == pytest.approx(moved.x, abs=0.2 * SILENT_STOP + 0.03 + hidden), (odo, moved, hidden)
        stats = rig.stats()
        assert stats["silent_stops"] >= 1 and stats["stall_stops"] >= 1, stats
        # the host's base link lost the silent device (a write timeout or no data) and reopened it ...
        assert backend.base.stats().link_losses > losses0 and backend.base.stats().reopens > 0
        # ... and goes on: the robot drives again
        with running.lock:
            before = robot.pose
        assert drive_for(running, backend, 180.0, until=lambda: robot.pose.relative_to(before).x > 0.05)
    finally:
        backend.close()
        running.stop()
        hw.stop()
