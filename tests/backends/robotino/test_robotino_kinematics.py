"""Omni-drive kinematics, odometry integration and host-side ramping."""
import math

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from backends.robotino.kinematics import OdometryIntegrator, OmniKinematics, round_half_away
from backends.robotino.ramp import RampLimits, ramp

KIN = OmniKinematics()
K = 60 * 32 / (2 * math.pi * 0.06)          # rpm per m/s at the rim, ~5092.96


def test_k_and_forward_by_hand():
    assert KIN.k == pytest.approx(5092.958, abs=1e-3)
    m1, m2, m3 = KIN.forward(0.1, 0.0, 0.0)
    assert (m1, m2, m3) == pytest.approx((-K * math.sqrt(3) / 2 * 0.1, 0.0, K * math.sqrt(3) / 2 * 0.1))
    assert KIN.forward(0.0, 0.2, 0.0) == pytest.approx((K * 0.1, -K * 0.2, K * 0.1))
    # pure rotation: all three motors at k * rb * omega
    assert KIN.forward(0.0, 0.0, 1.0) == pytest.approx((K * 0.175,) * 3)


@settings(max_examples=200, deadline=None)
@given(st.floats(-1, 1), st.floats(-1, 1), st.floats(-3, 3))
def test_inverse_undoes_forward(vx, vy, w):
    assert KIN.inverse(*KIN.forward(vx, vy, w)) == pytest.approx((vx, vy, w), abs=1e-9)


def test_setpoints_round_half_away_and_clamp():
    assert round_half_away(2.5) == 3 and round_half_away(-2.5) == -3 and round_half_away(-2.4) == -2
    assert KIN.setpoints(0.0, 0.0, 1.0) == (891, 891, 891)           # 891.27
    assert KIN.setpoints(1.0, 0.0, 0.0) == (-3000, 0, 3000)           # 4410.6 clamped
    assert KIN.setpoints(0.0, -0.1, 0.0) == (-255, 509, -255)         # -254.6, 509.3


@given(st.floats(-1.5, 1.5), st.floats(-1.5, 1.5), st.floats(-4, 4))
def test_a_command_beyond_the_motors_is_scaled_whole(vx, vy, w):
    """Beyond 3000 rpm on a motor the whole command shrinks: the same
    direction and curve, every motor within reach, the fastest at the limit."""
    cx, cy, cw = KIN.clamped(vx, vy, w)
    rpm = KIN.forward(cx, cy, cw)
    assert max(abs(m) for m in rpm) <= KIN.rpm_max + 1e-6
    top = max(abs(m) for m in KIN.forward(vx, vy, w))
    scale = min(1.0, KIN.rpm_max / top) if top > 0 else 1.0
    assert (cx, cy, cw) == pytest.approx((vx * scale, vy * scale, w * scale), abs=1e-9)
    assert all(abs(a - b) <= 0.5 for a, b in zip(KIN.setpoints(vx, vy, w), rpm))


def test_odometry_straight_and_turning():
    odo = OdometryIntegrator(KIN)
    rpm = KIN.forward(0.3, 0.0, 0.0)
    for _ in range(200):
        odo.update(rpm, 0.005)
    assert (odo.x, odo.y, odo.phi) == pytest.approx((0.3, 0.0, 0.0), abs=1e-9)
    odo.reset()
    rpm = KIN.forward(0.0, 0.0, math.pi / 2)
    for _ in range(400):
        odo.update(rpm, 0.005)
    assert odo.phi == pytest.approx(math.pi) and odo.x == pytest.approx(0.0, abs=1e-9)
    odo.reset()
    rpm = KIN.forward(0.2, 0.0, 0.5)       # a circle of radius 0.4 m
    for _ in range(int(math.pi / 0.5 / 0.001)):
        odo.update(rpm, 0.001)
    assert (odo.x, odo.y) == pytest.approx((0.0, 0.8), abs=2e-3)
    assert (odo.vx, odo.vy, odo.omega) == pytest.approx((0.2, 0.0, 0.5))


def test_ramp_accelerates_and_decelerates_within_limits():
    lim = RampLimits()
    assert ramp((0, 0, 0), (1.0, -1.0, 2.0), 0.1, lim) == pytest.approx((0.08, -0.08, 0.16))
    assert ramp((1.0, 0, 3.0), (0, 0, 0), 0.1, lim) == pytest.approx((0.85, 0, 3.0 - 0.314))
    # reversing direction decelerates first
    assert ramp((0.5, 0, 0), (-0.5, 0, 0), 0.1, lim)[0] == pytest.approx(0.35)
    assert ramp((0.0, 0, 0), (0.05, 0, 0), 0.1, lim)[0] == 0.05
