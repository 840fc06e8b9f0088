"""check_backend over every registered backend (entry point group ``rll_bt.backends``),
each on what it drives: sim (a PyBullet world of its own, and one a caller steps),
scripted, robotino on its firmware emulator (pty; bare, and with the laser, camera and
gripper of a robot configuration over emulated devices, and on the world's emulated
hardware), robotino_rest on its HTTP stand-in (bare, and with the same parts), remote on a
world served over TCP.  A backend registered without a case here fails."""
from __future__ import annotations

import threading
import time
from contextlib import contextmanager

import pytest

from rll_bt import plugins
from rll_bt.backend import Capability, Pose2D, available_backends, check_backend, open_backend


@contextmanager
def sim_standalone(**options):
    """The entry point as the command line uses it: a headless world that follows the wall clock."""
    yield open_backend("sim", seed=2, **options), time.sleep


@contextmanager
def sim_in_a_stepped_world():
    """A robot in a world its owner steps (how a game uses it): time passes by stepping."""
    from backends.sim.world import World
    world = World("rcll2016", seed=3, perception="rendered")
    try:
        yield open_backend("sim", world=world, robot=1), world.step
    finally:
        world.close()


@contextmanager
def scripted():
    yield open_backend("scripted"), time.sleep


@contextmanager
def robotino():
    from backends.robotino.emulator import RobotinoEmulator
    with RobotinoEmulator(gripper=True) as emu:
        yield open_backend("robotino", device=emu.device, gripper_device=emu.gripper_device), time.sleep


@contextmanager
def robotino_with_parts(laser="urg"):
    """A configured robot: base, gripper, laser and camera, each on its emulated device."""
    from backends.robotino.rig import EmulatedRobot
    rig = EmulatedRobot(laser=laser, holding_sensor="distance:8>1.5").start()
    try:
        yield open_backend("robotino", robot_config=rig.config()), time.sleep
    finally:
        rig.stop()


@contextmanager
def robotino_with_a_tim():
    with robotino_with_parts(laser="tim") as case:
        yield case


@contextmanager
def robotino_on_the_worlds_hardware():
    """The robotino backend on devices the PyBullet world feeds, the world stepped by a thread."""
    from backends.sim.hardware import WorldHardware
    from backends.sim.world import World
    world = World("rcll2016", seed=3)
    world.add_robot("CYAN", 1, pose=Pose2D(3.0, 2.0, 0.3))
    hw = WorldHardware(world, laser="urg", camera_fps=5.0)
    rig = hw.add(("CYAN", 1))
    stop = threading.Event()

    def run():
        last = time.monotonic()
        while not stop.is_set():
            now = time.monotonic()
            if now - last >= 0.01:
                world.step(min(now - last, 0.1))
                last = now
            hw.sync()
            time.sleep(0.005)
    thread = threading.Thread(target=run, daemon=True)
    thread.start()
    try:
        yield open_backend("robotino", robot_config=rig.config()), time.sleep
    finally:
        stop.set()
        thread.join(5)
        hw.stop()
        world.close()


@contextmanager
def robotino_rest():
    from backends.robotino_rest.standin import RestStandIn
    with RestStandIn() as standin:
        yield open_backend("robotino_rest", base_url=standin.url), time.sleep


@contextmanager
def robotino4_with_parts():
    """A Robotino 4 (REST stand-in) with the laser, camera and gripper of a robot configuration."""
    from backends.robotino.rig import EmulatedRobot
    from backends.robotino_rest.standin import RestStandIn
    rig = EmulatedRobot(laser="urg").start()
    try:
        with RestStandIn() as robot4:
            cfg = rig.config()
            cfg["base"] = {"type": "robotino4", "url": robot4.url}
            yield open_backend("robotino", robot_config=cfg), time.sleep
    finally:
        rig.stop()


@contextmanager
def remote():
    """A world in this process serving its robot over TCP, stepped on the wall clock by a thread."""
    from backends.sim.backend import SimBackend
    from backends.sim.world import World
    world = World("rcll2016", seed=4, perception="oracle")
    robot = SimBackend(world, ("CYAN", 1))
    server = plugins.load("rll_bt.backends", "remote").serve(
        lambda team, n: robot if (team, n) == ("CYAN", 1) else None, world.clock.now)
    stop = threading.Event()

    def serve():
        last = time.monotonic()
        while not stop.is_set():
            server.poll(0.005)
            now = time.monotonic()
            world.step(now - last)
            last = now
    thread = threading.Thread(target=serve, daemon=True)
    thread.start()
    try:
        yield open_backend("remote", address=f"127.0.0.1:{server.port}", robot=1), time.sleep
    finally:
        stop.set()
        thread.join(5)
        server.close()
        world.close()


CASES = {
    "sim": [sim_standalone, sim_in_a_stepped_world],
    "scripted": [scripted],
    "robotino": [robotino, robotino_with_parts, robotino_with_a_tim, robotino_on_the_worlds_hardware],
    "robotino_rest": [robotino_rest, robotino4_with_parts],
    "remote": [remote],
}


def test_every_registered_backend_has_a_case():
    assert set(available_backends()) <= set(CASES), "add a check_backend case for the new backend"


@pytest.mark.parametrize("case", [c for cases in CASES.values() for c in cases], ids=lambda c: c.__name__)
def test_the_backend_keeps_the_contract(case):
    with case() as (backend, advance):
        report = check_backend(backend, advance=advance, wait=120.0)     # waits bound a hang only
    assert report.ok and report.capabilities & Capability.DRIVE
    assert "leaving the context" in report.checked


def test_what_each_backend_advertises():
    """The capabilities checked above are the ones each backend is meant to have."""
    expected = {
        sim_standalone: Capability.DRIVE | Capability.ODOMETRY | Capability.LASER | Capability.CAMERA
        | Capability.GRIPPER | Capability.BUMPER | Capability.BATTERY | Capability.DETECTIONS,
        robotino: Capability.DRIVE | Capability.ODOMETRY | Capability.BUMPER | Capability.BATTERY
        | Capability.GRIPPER,
        robotino_rest: Capability.DRIVE | Capability.ODOMETRY | Capability.BUMPER | Capability.LASER
        | Capability.CAMERA,
        robotino_with_parts: Capability.DRIVE | Capability.ODOMETRY | Capability.BUMPER | Capability.BATTERY
        | Capability.GRIPPER | Capability.LASER | Capability.CAMERA,
    }
    for case, caps in expected.items():
        with case() as (backend, _advance):
            try:
                assert backend.capabilities == caps, case.__name__
            finally:
                backend.close()
