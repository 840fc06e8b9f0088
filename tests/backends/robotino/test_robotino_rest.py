"""The Robotino 4 REST backend against a local HTTP stand-in of restapid."""
import math
import time

import numpy as np
import pytest

from backends.robotino_rest import RobotinoRestBackend
from backends.robotino_rest.standin import RestStandIn
from rll_bt.backend import BackendUnavailable, Capability, CapabilityError, open_backend


@pytest.fixture
def standin():
    with RestStandIn() as s:
        yield s


def test_standin_stops_the_robot_without_refresh(standin):
    from backends.robotino_rest.client import RestClient
    client = RestClient(standin.url)
    client.send_json("/data/omnidrive", [0.2, 0.0, 0.0])
    assert standin.moving()
    time.sleep(0.3)
    assert not standin.moving() and standin.stops == 1
    assert standin.pose[0] == pytest.approx(0.2 * 0.2, abs=0.005)


def test_omnidrive_is_refreshed_while_moving(standin, wait_for):
    robot = open_backend("robotino_rest", base_url=standin.url)
    try:
        assert isinstance(robot, RobotinoRestBackend)
        robot.drive(0.3, 0.0, 0.5)            # one command, then only the backend's own refresh
        time.sleep(0.45)
        assert standin.moving() and standin.stops == 0
        times = [t for t, _ in standin.commands]
        assert max(np.diff(times)) < 0.2
        assert standin.commands[-1][1] == [0.3, 0.0, 0.5]
        # the host deadman (0.5 s) ends the refresh; one zero command follows
        assert wait_for(lambda: not standin.moving(), 0.8)
        assert standin.commands[-1][1] == [0.0, 0.0, 0.0] and standin.stops == 0
        assert robot.deadman_stops == 1
    finally:
        robot.close()


def test_odometry_bumper_distances(standin):
    with RobotinoRestBackend(standin.url) as robot:
        for _ in range(10):
            robot.drive(0.2, 0.0, 0.0)
            time.sleep(0.05)
        robot.stop()
        assert not standin.moving()
        odo = robot.odometry()
        assert odo.pose.x == pytest.approx(standin.pose[0], abs=1e-6)
        assert 0.07 < odo.pose.x < 0.14
        assert robot.bumper() is False
        standin.bumper = True
        assert robot.bumper() is True
        standin.distances[4] = 1.75
        assert robot.distance_sensors()[4] == 1.75 and len(robot.distance_sensors()) == 9
        assert robot.capabilities & Capability.LASER and not robot.capabilities & Capability.GRIPPER
        with pytest.raises(CapabilityError):
            robot.battery()


def test_laser_scan_and_camera(standin):
    standin.scan_ranges[0] = 10.0               # beyond range_max -> inf
    standin.scan_ranges[1] = 0.5
    robot = RobotinoRestBackend(standin.url)
    try:
        scan = robot.laser_scan()
        assert len(scan.ranges) == 360 and scan.angle_min == pytest.approx(-math.pi)
        assert np.isinf(scan.ranges[0]) and scan.ranges[1] == 0.5 and scan.ranges[2] == 2.0
        assert scan.angles[180] == pytest.approx(0.0, abs=1e-9)
        image = robot.camera_image()
        assert image.image.shape == (240, 320, 3)
        b, g, r = image.image[120, 40]
        assert r > 200 and g < 60                 # left half red in BGR
        assert image.intrinsics.width == 320 and image.intrinsics.cx == 160
    finally:
        robot.close()


def test_put_method_and_unreachable_server(standin, wait_for):
    robot = RobotinoRestBackend(standin.url, method="PUT")
    try:
        robot.drive(0.1, 0.1, 0.0)
        assert wait_for(lambda: ("PUT", "/data/omnidrive") in standin.requests, 2.0)
    finally:
        robot.close()
    port = standin.url.rsplit(":", 1)[1]
    standin.stop()
    with pytest.raises(BackendUnavailable, match="not reachable"):
        RobotinoRestBackend(f"http://127.0.0.1:{port}", timeout=0.2)
    with pytest.raises(ValueError):
        RobotinoRestBackend("ftp://robot")
