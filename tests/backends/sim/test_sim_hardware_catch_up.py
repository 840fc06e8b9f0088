"""A hardware game's world that stood still a moment (its process not
scheduled) and catches up: the steps over the wall time gone by move the
robot at the wheels' speeds of then (backends/sim/hardware_parts.WheelTrack),
so the world's robot ends where the host's odometry, integrated from the
wheels the firmware turned all along, says it is.  At the wheels' speeds of
now, a robot that stopped meanwhile lost in the world the motion its
odometry counted."""
import threading
import time

import pytest

from backends.sim.hardware import WorldHardware
from games.world_pace import world_advance
from rll_bt.backend import Pose2D, SensorLost, open_backend
from tests.backends.sim.test_sim_hardware import fresh, late_motion


class GamePace:
    """The world stepped as a hardware game steps it (games/processes.ProcessGame._tick with
    HardwareGame.catch_up): by the wall time passed, at most 0.1 s a step, catching up what it fell
    behind, each step followed by the devices' sync at the wall time it stands for; ``hold`` stops it."""

    def __init__(self, world, hw):
        self.world, self.hw = world, hw
        self.lock = threading.Lock()
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._loop, daemon=True)
        self._thread.start()

    def _loop(self):
        last = time.monotonic()
        while not self._stop.is_set():
            with self.lock:
                dt, stands = world_advance(last, time.monotonic(), 0.1, 2.0)
                if dt >= 0.005:
                    self.world.step(dt)
                    self.hw.sync(at=stands)
                    last = stands
            time.sleep(0.005)

    def run(self, seconds, until=None):
        end = time.monotonic() + seconds
        while time.monotonic() < end:
            if until is not None and until():
                return True
            time.sleep(0.01)
        return until() if until is not None else True

    def stop(self):
        self._stop.set()
        self._thread.join(timeout=2)


def command(backend, pace, seconds, vx):
    end = time.monotonic() + seconds
    while time.monotonic() < end:
        try:
            backend.drive(vx, 0.0, 0.0)
        except SensorLost:
            pass
        time.sleep(0.02)


@pytest.mark.parametrize("devices", ["threads", "process"])
def test_a_world_that_catches_up_moves_the_robot_as_the_wheels_turned_meanwhile(make_world, devices):
    world = make_world("rcll2016", seed=3)
    world.add_robot("CYAN", 1, pose=Pose2D(3.0, 2.0, 0.3), laser_noise=0.0)
    hw = WorldHardware(world, laser="urg", camera_fps=1.0, devices=devices)
    rig = hw.add(("CYAN", 1))
    pace = GamePace(world, hw)
    backend = open_backend("robotino", robot_config=rig.config())
    robot = world.robots[("CYAN", 1)]
    try:
        fresh(pace, lambda: backend.drive(0.0, 0.0, 0.0))
        pace.run(0.5)
        with pace.lock:
            start, odo0 = robot.pose, backend.odometry().pose
        cycles0 = len(backend.base.cycle_periods())
        command(backend, pace, 0.6, 0.3)               # under way
        with pace.lock:                                # the world's process not scheduled for 1.2 s ...
            command(backend, pace, 0.6, 0.3)           # ... while the wheels turn on, then stop
            backend.stop()
            time.sleep(0.6)
        assert pace.run(180.0, until=lambda: backend.odometry().vx == 0.0 and robot.velocity[0] == 0.0)
        pace.run(0.5)
        with pace.lock:
            moved, odo = robot.pose.relative_to(start), backend.odometry().pose.relative_to(odo0)
        periods = backend.base.cycle_periods()
        hidden = late_motion(periods[min(cycles0, len(periods)):], 0.3)
        assert odo.x > 0.3, odo                        # it drove on while the world stood
        assert moved.x == pytest.approx(odo.x, abs=0.04 + hidden), (moved, odo, hidden)
    finally:
        backend.close()
        pace.stop()
        hw.stop()
