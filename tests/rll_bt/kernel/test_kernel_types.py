import math
import threading

import numpy as np
import pytest

from rll_bt.backend import CameraExtrinsics, CameraIntrinsics, LightDetection, Pose2D, light_state_code, wrap_angle
from rll_bt.clock import SimClock, WallClock


def test_pose_compose_inverse_roundtrip():
    a = Pose2D(1.0, 2.0, math.pi / 2)
    b = Pose2D(0.5, 0.0, 0.0)
    c = a.compose(b)
    assert c.x == pytest.approx(1.0) and c.y == pytest.approx(2.5) and c.theta == pytest.approx(math.pi / 2)
    back = c.relative_to(a)
    assert (back.x, back.y, back.theta) == pytest.approx((0.5, 0.0, 0.0))
    ident = a.compose(a.inverse())
    assert (ident.x, ident.y, ident.theta) == pytest.approx((0, 0, 0), abs=1e-12)


def test_wrap_angle():
    assert wrap_angle(3 * math.pi) == pytest.approx(-math.pi)
    assert wrap_angle(-0.1) == pytest.approx(-0.1)


def test_camera_rotation_forward_level():
    r = CameraExtrinsics(yaw=0.0, pitch=0.0).rotation()
    # optical z (forward) is robot x, optical x (right) is robot -y, optical y (down) is robot -z
    assert np.allclose(r @ [0, 0, 1], [1, 0, 0])
    assert np.allclose(r @ [1, 0, 0], [0, -1, 0])
    assert np.allclose(r @ [0, 1, 0], [0, 0, -1])
    down = CameraExtrinsics(pitch=math.radians(30)).rotation() @ [0, 0, 1]
    assert down[2] < 0 and down[0] > 0           # pitch positive looks down
    left = CameraExtrinsics(yaw=math.pi / 2).rotation() @ [0, 0, 1]
    assert np.allclose(left, [0, 1, 0])


def test_intrinsics_from_fov():
    k = CameraIntrinsics.from_fov(640, 480, math.radians(90))
    assert k.fx == pytest.approx(320) and k.cx == 320 and k.matrix[1, 2] == 240


def test_light_code_is_formula_1():
    assert light_state_code(True, False, False) == 1
    assert light_state_code(False, True, False) == 2
    assert light_state_code(False, False, True) == 4
    assert LightDetection((0, 0, 1, 1), 6).lights == {"green": False, "yellow": True, "red": True}


def test_sim_clock_advances_only_when_told():
    c = SimClock()
    assert c.now() == 0.0
    c.advance(1.5)
    assert c.now() == 1.5 and c.epoch() == pytest.approx(1_700_000_001.5)
    with pytest.raises(ValueError):
        c.advance(-1)
    c.sleep(0.5)                     # the owning thread advances
    assert c.now() == 2.0


def test_sim_clock_sleep_from_other_thread_waits_for_owner():
    c = SimClock()
    woke = threading.Event()

    def sleeper():
        c.sleep(1.0)
        woke.set()

    t = threading.Thread(target=sleeper)
    t.start()
    assert not woke.wait(0.1)
    c.advance(0.5)
    assert not woke.wait(0.1)
    c.advance(0.6)
    assert woke.wait(2.0)
    t.join()


def test_wall_clock_moves():
    w = WallClock()
    t0 = w.now()
    w.sleep(0.01)
    assert w.now() > t0 and w.epoch() > 1.6e9
