"""A simulated robot as emulated hardware (real ptys, sockets and HTTP): the
robotino backend drives the world's robot through the base firmware, its
laser scans decode to the ranges the world computes, its camera frames are
the world's renders, its gripper moves the world's gripper."""
import math
import threading
import time
from types import SimpleNamespace

import numpy as np
import pytest

from backends.sim import sensors
from backends.sim.hardware import WorldHardware
from rll_bt.backend import Pose2D, SensorLost, open_backend


class Running:
    """The world stepped on the wall clock in a thread of its own (as the game
    process does), the devices synced after each step; ``lock`` holds it
    while a test reads PyBullet itself.  A loop that came late (a loaded
    machine) catches up in steps of at most 50 ms, each followed by a sync,
    so the world's time keeps to the wall clock the host and the emulators
    live on."""

    def __init__(self, world, hw):
        self.world, self.hw = world, hw
        self.lock = threading.Lock()
        self._stop = threading.Event()
        self.longest_gap = 0.0              # the longest wall time between two syncs (reset by a test)
        self._thread = threading.Thread(target=self._loop, daemon=True)
        self._thread.start()

    def _loop(self):
        last = time.monotonic()
        while not self._stop.is_set():
            with self.lock:
                lag = time.monotonic() - last
                self.longest_gap = max(self.longest_gap, lag)
                if lag > 1.0:                       # more than the world can catch up: let it go
                    last += lag - 1.0
                    lag = 1.0
                while lag >= 0.01 and not self._stop.is_set():
                    h = min(lag, 0.05)
                    self.world.step(h)
                    self.hw.sync()
                    last += h
                    lag -= h
                self.hw.sync()
            time.sleep(0.005)

    def stop(self):
        self._stop.set()
        self._thread.join(timeout=2)

    def run(self, seconds, until=None):
        end = time.monotonic() + seconds
        while time.monotonic() < end:
            if until is not None and until():
                return True
            time.sleep(0.01)
        return until() if until is not None else True


def fresh(running, read, seconds=30.0):
    """``read()`` once its device has a fresh reading: a loaded machine can leave
    the world's laser or camera stale for a moment (SensorLost), retried up to
    ``seconds``."""
    end = time.monotonic() + seconds
    while True:
        try:
            return read()
        except SensorLost:
            if time.monotonic() > end:
                raise
            running.run(0.1)


@pytest.fixture(params=[("urg", "threads"), ("tim", "threads"), ("urg", "process")], ids=lambda p: "-".join(p))
def rigged(request, make_world):
    """A robot's devices on the world: as threads of this process, or in a process of their own."""
    laser, devices = request.param
    world = make_world("rcll2016", seed=3)
    world.add_robot("CYAN", 1, pose=Pose2D(3.0, 2.0, 0.3), laser_noise=0.0)
    hw = WorldHardware(world, laser=laser, camera_fps=1.0, devices=devices)     # renders hold the GIL: few
    rig = hw.add(("CYAN", 1))
    running = Running(world, hw)
    backend = open_backend("robotino", robot_config=rig.config())
    yield world, hw, rig, backend, running
    backend.close()
    running.stop()
    hw.stop()


def test_scans_decode_to_the_ranges_the_world_computes(rigged):
    world, hw, rig, backend, running = rigged
    running.run(0.5)
    scan = fresh(running, backend.laser_scan)
    robot = world.robots[("CYAN", 1)]
    with running.lock:
        truth = sensors.laser_ranges(world.cid, robot, rig.angles, noisy=False)
    kind, model = laser_model(rig)
    if kind == "urg":
        m = model
        truth = truth[m.amin:m.amax + 1]
        limit = m.dmax / 1000.0
    else:
        limit = model.range_mm[1] / 1000.0
    assert len(scan.ranges) == len(truth)
    seen = np.isfinite(truth) & (truth <= limit)
    assert seen.sum() > 0.5 * len(truth)
    assert np.allclose(scan.ranges[seen], truth[seen], atol=0.0006)          # millimetres on the wire
    assert np.all(np.isinf(scan.ranges[~seen]))
    angles = scan.angle_min + scan.angle_increment * np.arange(len(scan.ranges))
    expected = rig.angles[m.amin:m.amax + 1] if kind == "urg" else rig.angles
    assert np.allclose(angles, expected, atol=1e-4)
    assert scan.mount.x == pytest.approx(robot.config.geometry.laser_mount[0])
    # turning, each scan is stamped when the world cast its ranges (not when the device sent them, up to
    # a scan period later: 0.16 rad off the odometry at 1.6 rad/s, the localiser lost the robot)
    cast = []
    backend.drive(0.0, 0.0, 0.8)
    running.run(0.4)                # turning: no two casts alike (the laser has no noise)
    put = rig._put_ranges
    rig._put_ranges = lambda mm, *at: (cast.append((time.monotonic(), np.round(mm))), put(mm, *at))
    stamps = {}
    end = time.monotonic() + 3.0
    while time.monotonic() < end and len(stamps) < 20:
        backend.drive(0.0, 0.0, 0.8)
        scan = fresh(running, backend.laser_scan)
        stamps[scan.stamp] = np.where(np.isfinite(scan.ranges), np.round(scan.ranges * 1000.0), 0.0)
        running.run(0.03)
    backend.stop()
    beams = slice(m.amin, m.amax + 1) if kind == "urg" else slice(0, len(rig.angles))
    offsets = []
    for stamp, mm in stamps.items():
        match = [at for at, c in list(cast) if np.array_equal(np.where(mm > 0, c[beams], 0.0), mm)]
        if len(match) == 1:
            offsets.append(stamp - match[0])
    assert len(offsets) >= 8, (len(stamps), len(offsets))
    # before: 0.05 on average, each scan anywhere from 0 to 0.15 s after its cast. Now every scan
    # is the same time after its cast: 0.003-0.011 s on a quiet machine; under the suite's load a
    # constant 0.03-0.046 s (the emulator sends a scan when due, a fixed phase after the world's
    # cast, and the host's clock mapping cannot see a constant delay), so the spread is the test
    off = np.asarray(offsets)
    assert np.percentile(off, 90) - np.percentile(off, 10) < 0.01, offsets
    assert np.median(np.abs(off)) < 0.1, offsets             # within one scan period


def laser_model(rig):
    """(kind, the device model) of a rig's laser (the default models of the configuration's type)."""
    from backends.devices.laser import tim_device, urg_device
    kind = rig.config()["laser"]["type"]
    return kind, (urg_device.MODELS["URG-04LX"] if kind == "urg" else tim_device.MODELS["TiM571"])


def drive_episode(world, rig, backend, running, seconds=1.5):
    """Drive ahead at 0.2 m/s for ``seconds``, stop, let it settle.  Returns the
    world's motion, the host's odometry, the watchdog stops of the episode and
    the longest time the real-time chain went without its cycle (the base not
    hearing the host, or the world not stepped): what a loaded machine took."""
    robot = world.robots[("CYAN", 1)]
    start, odo0 = robot.pose, backend.odometry().pose
    stops0, t0 = rig.stats()["watchdog_motion_stops"], time.monotonic()
    running.longest_gap = 0.0
    end, lost = t0 + seconds, False
    while time.monotonic() < end:
        try:
            backend.drive(0.2, 0.0, 0.0)
        except SensorLost:                  # the world's laser went stale: the backend stopped the robot
            lost = True
            break
        running.run(0.05)
    backend.stop()
    running.run(0.8)
    if lost:
        fresh(running, lambda: backend.drive(0.0, 0.0, 0.0))
    if hasattr(rig, "rig"):                         # devices in this process: when the base heard the host
        emu = rig.rig.base
        with emu.lock:                              # the emulator's thread appends to the log
            heard = [t for t, _ in emu.firmware.rx_log if t >= t0]
        silence = max(np.diff(heard), default=math.inf) if len(heard) > 1 else math.inf
    else:
        silence = 0.0
    return SimpleNamespace(moved=robot.pose.relative_to(start), odo=backend.odometry().pose.relative_to(odo0),
                           stops=rig.stats()["watchdog_motion_stops"] - stops0,
                           starved=math.inf if lost else max(silence, running.longest_gap))


def test_the_base_drives_the_worlds_robot_and_the_camera_shows_the_worlds_view(rigged):
    world, hw, rig, backend, running = rigged
    robot = world.robots[("CYAN", 1)]
    # a real-time property: an episode in which the machine left the base without the host's polls, or the
    # world without steps, for 250 ms or more (near the watchdog's 300 ms), or the world's laser stale, tests
    # the machine, not the code, and is driven again (at most five times; the last one is asserted whatever
    # it was)
    for _ in range(5):
        ep = drive_episode(world, rig, backend, running)
        if ep.starved < 0.25:
            break
    moved, odo = ep.moved, ep.odo
    assert 0.15 < moved.x < 0.4 and abs(moved.y) < 0.03, ep
    # the host's odometry, integrated from the wheel speeds it polls, follows the world's motion
    assert odo.x == pytest.approx(moved.x, abs=0.08), (ep, rig.stats())
    assert ep.stops == 0, ep
    frame = fresh(running, backend.camera_image)
    assert frame.image.shape == (240, 320, 3) and abs(frame.stamp - time.monotonic()) < 1.5
    assert frame.intrinsics.fx == pytest.approx(160 / math.tan(robot.config.camera_hfov / 2), rel=1e-3)
    assert frame.image.std() > 5                                     # a rendered view, not a blank


def test_the_gripper_moves_the_worlds_gripper_and_holding_comes_from_the_world(rigged):
    world, hw, rig, backend, running = rigged
    robot = world.robots[("CYAN", 1)]
    assert running.run(30.0, until=lambda: backend.gripper_status().state.value == "idle")
    backend.gripper_move(0.05, 0.02, 0.4)
    assert running.run(30.0, until=lambda: np.allclose(robot.gripper.position, (0.05, 0.02, 0.4), atol=0.002)
                       and backend.gripper_status().state.value == "idle")
    assert np.allclose(backend.gripper_status().position, (0.05, 0.02, 0.4), atol=0.002)
    assert backend.holding() is False
    running.stop()                          # what the world says is in the jaws reaches the host
    robot.holding = 1                       # (no such workpiece: the world is not stepped any more)
    end = time.monotonic() + 30.0
    while backend.holding() is not True and time.monotonic() < end:
        hw.sync()
        time.sleep(0.02)
    assert backend.holding() is True
    robot.holding = None
