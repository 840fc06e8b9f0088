"""Path follower limits, and the laser stop distance."""
import math

import numpy as np
import pytest

from rll_bt.backend import Pose2D
from skills.navigation import Limits, PathFollower, clear_distance, speed_limit


def simulate(follower, pose, dt=0.1, steps=400, cap=None):
    """Integrate the commanded robot-frame velocity exactly; returns the
    commands (field frame) and the final pose."""
    cmds = []
    for _ in range(steps):
        vx, vy, w = follower.command(pose, dt, cap)
        c, s = math.cos(pose.theta), math.sin(pose.theta)
        cmds.append((c * vx - s * vy, s * vx + c * vy, w))
        pose = Pose2D(pose.x + (c * vx - s * vy) * dt, pose.y + (s * vx + c * vy) * dt, pose.theta + w * dt)
        if follower.done:
            break
    return np.array(cmds), pose


def test_follower_respects_speed_and_acceleration_limits_and_reaches_the_goal():
    lim = Limits(max_speed=0.7, max_omega=1.6, max_accel=0.8, max_decel=1.2, max_alpha=1.6)
    path = np.array([[0.0, 0.0], [3.0, 0.0], [3.0, 2.0]])
    f = PathFollower(path, math.pi, lim)
    cmds, end = simulate(f, Pose2D(0.0, 0.0, 0.0))
    assert f.done
    assert math.hypot(end.x - 3.0, end.y - 2.0) <= 0.05
    assert abs(math.remainder(end.theta - math.pi, 2 * math.pi)) <= 0.05
    speed = np.hypot(cmds[:, 0], cmds[:, 1])
    assert speed.max() <= 0.7 + 1e-9 and speed.max() > 0.6
    dv = np.hypot(*np.diff(cmds[:, :2], axis=0).T)
    assert dv.max() <= 1.2 * 0.1 + 1e-9                  # never more than max_decel * dt
    accel_steps = np.diff(speed) > 0
    assert (np.diff(speed)[accel_steps]).max() <= 0.8 * 0.1 + 1e-9
    assert np.abs(cmds[:, 2]).max() <= 1.6 + 1e-9
    assert np.abs(np.diff(cmds[:, 2])).max() <= 1.6 * 0.1 + 1e-9


def test_follower_faces_the_direction_of_travel_far_from_the_goal():
    f = PathFollower(np.array([[0.0, 0.0], [0.0, 5.0]]), 0.0, Limits())
    pose = Pose2D(0.0, 0.0, 0.0)
    for _ in range(30):
        _, pose = simulate(f, pose, steps=1)
    assert pose.theta == pytest.approx(math.pi / 2, abs=0.2)


def test_speed_cap_slows_and_stops_the_follower():
    f = PathFollower(np.array([[0.0, 0.0], [5.0, 0.0]]), None, Limits())
    cmds, end = simulate(f, Pose2D(), steps=100, cap=lambda ux, uy: 0.0)
    assert np.abs(cmds[:, :2]).max() == 0.0 and f.capped and not f.done
    f2 = PathFollower(np.array([[0.0, 0.0], [5.0, 0.0]]), None, Limits())
    cmds, _ = simulate(f2, Pose2D(), steps=50, cap=lambda ux, uy: 0.2)
    assert np.hypot(cmds[:, 0], cmds[:, 1]).max() <= 0.2 + 1e-9


def test_clear_distance_of_a_disc():
    pts = np.array([[1.0, 0.0], [1.0, 0.5], [-1.0, 0.0]])
    # straight ahead: the point at (1, 0) is met after 1 - radius
    assert clear_distance(pts, 1.0, 0.0, 0.2, 0.0) == pytest.approx(0.8)
    # sideways the (1, 0.5) point is 0.5 lateral: out of a 0.2 m disc's way
    assert clear_distance(pts[1:2], 1.0, 0.0, 0.2, 0.0) == math.inf
    # backwards only (-1, 0) matters
    assert clear_distance(pts, -1.0, 0.0, 0.2, 0.0) == pytest.approx(0.8)


def test_speed_limit_stops_in_time():
    pts = np.array([[1.0, 0.0]])
    v = speed_limit(pts, 1.0, 0.0, 0.2, 0.1, 0.0, 1.0, latency=0.1)
    free = 1.0 - 0.2 - 0.1
    assert v * 0.1 + v * v / 2.0 == pytest.approx(free)
    assert speed_limit(pts, 1.0, 0.0, 0.2, 0.9, 0.0, 1.0) == 0.0
    assert speed_limit(pts, 0.0, 1.0, 0.2, 0.1, 0.0, 1.0) == math.inf


def test_points_beside_the_robot_do_not_block_a_motion_past_them():
    from skills.navigation.safety import free_distance
    side = np.array([[0.0, 0.29]])                    # 6.5 cm from a 0.225 m robot, to its left
    assert free_distance(side, 1.0, 0.0, 0.225, 0.08, 0.08) == math.inf
    assert free_distance(side, 0.0, 1.0, 0.225, 0.08, 0.08) == 0.0      # but not toward it
    ahead = np.array([[0.28, 0.0]])                    # 5.5 cm in front: inside the margin
    assert free_distance(ahead, 1.0, 0.0, 0.225, 0.08, 0.08) == 0.0
    far = np.array([[1.0, 0.1]])
    assert free_distance(far, 1.0, 0.0, 0.225, 0.08, 0.08) == pytest.approx(
        1.0 - math.sqrt(0.305 ** 2 - 0.01) - 0.08)
