"""check_backend finds what breaks the backend contract, one kind of break at a time,
on a small backend that keeps it (and that each test breaks in one way)."""
from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest

from rll_bt.backend import (
    Backend,
    BackendContractError,
    Battery,
    CameraExtrinsics,
    CameraImage,
    CameraIntrinsics,
    Capability,
    CapabilityError,
    Detections,
    GripperState,
    GripperStatus,
    LaserScan,
    LightDetection,
    Odometry,
    Pose2D,
    TagDetection,
    check_backend,
)
from rll_bt.backend.check import METHODS
from rll_bt.clock import SimClock

ALL = (Capability.DRIVE | Capability.ODOMETRY | Capability.LASER | Capability.CAMERA | Capability.GRIPPER
       | Capability.BUMPER | Capability.BATTERY | Capability.DETECTIONS)


class Good(Backend):
    """Every capability, on a simulated clock; the odometry integrates the last command."""

    name = "good"

    def __init__(self, caps=ALL):
        self.clock = SimClock(100.0)
        self.caps = caps
        self.vel = (0.0, 0.0, 0.0)
        self.pose = Pose2D()
        self.t = self.clock.now()
        self.closed = 0
        self.opened = True

    def advance(self, seconds):
        self._integrate()
        self.clock.advance(seconds)
        self._integrate()

    def _integrate(self):
        dt, self.t = self.clock.now() - self.t, self.clock.now()
        vx, vy, w = self.vel
        self.pose = Pose2D(self.pose.x + vx * dt, self.pose.y + vy * dt, self.pose.theta + w * dt)

    @property
    def capabilities(self):
        return self.caps

    def _need(self, cap):
        if not self.caps & cap:
            raise CapabilityError(f"no {cap}")

    def drive(self, vx, vy, omega):
        self._need(Capability.DRIVE)
        self._integrate()
        self.vel = (vx, vy, omega)

    def stop(self):
        self.drive(0.0, 0.0, 0.0)

    def odometry(self):
        self._need(Capability.ODOMETRY)
        self._integrate()
        return Odometry(self.clock.now(), self.pose, *self.vel)

    def laser_scan(self):
        self._need(Capability.LASER)
        r = np.full(360, 2.0)
        r[0] = np.inf
        return LaserScan(self.clock.now(), -math.pi, 2 * math.pi / 360, 0.05, 5.6, r, Pose2D(0.1, 0.0, 0.0))

    def camera_image(self, camera="front"):
        self._need(Capability.CAMERA)
        return CameraImage(self.clock.now(), np.zeros((48, 64, 3), np.uint8),
                           CameraIntrinsics.from_fov(64, 48, math.radians(60)), CameraExtrinsics(), camera)

    def detections(self, camera="front"):
        self._need(Capability.DETECTIONS)
        return Detections(self.clock.now(), (TagDetection(5, (0.1, 0.0, 1.5), (0.0, math.pi, 0.0)),),
                          (LightDetection((10, 10, 8, 20), 5),), CameraExtrinsics())

    def bumper(self):
        self._need(Capability.BUMPER)
        return False

    def battery(self):
        self._need(Capability.BATTERY)
        return Battery(24.1, 1.2, 0.8, False)

    def gripper_status(self):
        self._need(Capability.GRIPPER)
        return GripperStatus(GripperState.IDLE, True, (0.0, 0.0, 0.05), False)

    def gripper_open(self):
        self._need(Capability.GRIPPER)

    def gripper_close(self):
        self._need(Capability.GRIPPER)

    def gripper_move(self, x, y, z):
        self._need(Capability.GRIPPER)

    def close(self):
        self.closed += 1
        self.opened = False


def problems(backend, **kw) -> list[str]:
    kw.setdefault("advance", backend.advance)
    with pytest.raises(BackendContractError) as exc:
        check_backend(backend, **kw)
    assert str(exc.value).count("\n- ") == len(exc.value.problems)
    return exc.value.problems


def one(backend, match, **kw) -> None:
    found = problems(backend, **kw)
    assert len(found) == 1 and match in found[0], found


def test_a_backend_that_keeps_the_contract_passes_and_ends_closed():
    b = Good()
    report = check_backend(b, advance=b.advance)
    assert report.ok and report.capabilities == ALL
    for what in ("laser_scan()", "camera_image('front')", "detections('front')", "gripper_close()",
                 "odometry() after stop()", "leaving the context", "close() again"):
        assert what in report.checked
    assert b.closed == 2 and "stop" not in vars(b) and "drive" not in vars(b)    # the wrappers are gone


def test_without_advance_nothing_needs_time_and_the_robot_is_not_driven():
    b = Good(Capability.DRIVE | Capability.ODOMETRY)
    report = check_backend(b, move=False)
    assert "drive(0.1, 0, 0)" not in report.checked and b.pose == Pose2D()
    assert "laser_scan() without LASER" in report.checked


def test_every_capability_has_its_methods():
    assert set(METHODS) == {c.name for c in Capability if c.name != "NONE"}
    for methods in METHODS.values():
        assert all(callable(getattr(Backend, m)) for m in methods)


def test_an_advertised_capability_that_raises():
    class NoLaser(Good):
        def laser_scan(self):
            raise CapabilityError("no laser after all")
    one(NoLaser(), "laser_scan(): advertised but raised CapabilityError")


def test_a_missing_capability_that_answers_anyway():
    one(type("Quiet", (Good,), {"bumper": lambda self: False})(ALL & ~Capability.BUMPER),
        "bumper() without BUMPER: returned instead of raising CapabilityError")


def test_a_missing_capability_that_raises_the_wrong_error():
    class Wrong(Good):
        def gripper_status(self):
            raise RuntimeError("no gripper here")
    found = problems(Wrong(ALL & ~Capability.GRIPPER))
    assert any("gripper_status() without GRIPPER: raised RuntimeError" in p for p in found)


@pytest.mark.parametrize("change, match", [
    (lambda s: replace(s, range_max=5600.0), "implausible"),                       # millimetres
    (lambda s: replace(s, angle_increment=1.0), "span more than a turn"),          # degrees
    (lambda s: replace(s, ranges=np.full(360, 2, dtype=np.int32)), "1-D float array"),
    (lambda s: replace(s, ranges=np.full((2, 180), 2.0)), "1-D float array"),
    (lambda s: replace(s, ranges=np.full(360, 9.0)), "must lie in [0, range_max"),
    (lambda s: replace(s, mount=(0.1, 0.0, 0.0)), "mount: expected a Pose2D"),
], ids=["millimetres", "degrees", "ints", "2-D", "beyond range_max", "mount"])
def test_laser_scans_with_wrong_types_shapes_or_units(change, match):
    class Bad(Good):
        def laser_scan(self):
            return change(super().laser_scan())
    one(Bad(), match)


def test_camera_images_must_be_bgr_bytes_matching_their_intrinsics():
    class Floats(Good):
        def camera_image(self, camera="front"):
            img = super().camera_image(camera)
            return CameraImage(img.stamp, img.image.astype(np.float32), img.intrinsics, img.extrinsics)
    one(Floats(), "H x W x 3 uint8")

    class Mismatch(Good):
        def camera_image(self, camera="front"):
            img = super().camera_image(camera)
            return CameraImage(img.stamp, img.image, CameraIntrinsics.from_fov(640, 480, 1.0), img.extrinsics)
    one(Mismatch(), "intrinsics are 640 x 480, the image 64 x 48")


def test_detections_light_states_and_tag_units():
    class Bad(Good):
        def detections(self, camera="front"):
            return Detections(self.clock.now(), (TagDetection(5, (100.0, 0.0, 1500.0), (0.0, 0.0, 0.0)),),
                              (LightDetection((1, 2, 3, 4), 9),))
    found = problems(Bad())
    assert any("tvec" in p and "implausible" in p for p in found) and any("not 0..7" in p for p in found)


def test_battery_in_millivolts_and_a_bad_state_of_charge():
    class Bad(Good):
        def battery(self):
            return Battery(24100.0, 0.0, 80.0)
    found = problems(Bad())
    assert any("voltage" in p and "implausible" in p for p in found) and any("soc" in p for p in found)


def test_gripper_status_types():
    class Bad(Good):
        def gripper_status(self):
            return GripperStatus("idle", 1, (0.0, 0.0), "yes")
    found = problems(Bad())
    for what in ("state: expected GripperState", "is_open: expected bool", "position", "holding"):
        assert any(what in p for p in found), what


def test_odometry_must_be_wrapped_and_never_go_back():
    class Unwrapped(Good):
        def odometry(self):
            o = super().odometry()
            return Odometry(o.stamp, Pose2D(o.pose.x, o.pose.y, 4.0), o.vx, o.vy, o.omega)
    found = problems(Unwrapped())
    assert found and all("not wrapped" in p for p in found)

    class Backwards(Good):
        n = 0

        def odometry(self):
            self.n += 1
            o = super().odometry()
            return Odometry(o.stamp - self.n, o.pose, o.vx, o.vy, o.omega)
    assert any("went back in time" in p for p in problems(Backwards()))


def test_readings_on_two_time_bases():
    class TwoClocks(Good):
        def laser_scan(self):
            s = super().laser_scan()
            return LaserScan(s.stamp + 3600.0, s.angle_min, s.angle_increment, s.range_min, s.range_max,
                             s.ranges, s.mount)
    one(TwoClocks(), "not on one time base")


def test_a_drive_that_does_not_move_and_a_stop_that_does_not_stop():
    class Stuck(Good):
        def drive(self, vx, vy, omega):
            self._need(Capability.DRIVE)
    one(Stuck(), "moved the odometry 0.000 m")

    class Runaway(Good):
        def stop(self):
            pass
    found = problems(Runaway())
    assert any("after stop() the odometry still moves" in p for p in found)


def test_a_sensor_that_never_delivers():
    class Silent(Good):
        def laser_scan(self):
            self._need(Capability.LASER)
            return None
    one(Silent(), "laser_scan(): advertised but nothing arrived in 2 s")


def test_leaving_the_context_must_stop_the_robot():
    class NoStopOnExit(Good):
        def __exit__(self, *exc):
            self.close()
    one(NoStopOnExit(), "leaving the context did not stop the robot")


def test_close_must_be_safe_twice():
    class Fragile(Good):
        def close(self):
            if not self.opened:
                raise RuntimeError("already closed")
            super().close()
    one(Fragile(), "close() a second time raised RuntimeError")


def test_not_a_backend_at_all():
    with pytest.raises(BackendContractError, match="is not a Backend"):
        check_backend(object())
