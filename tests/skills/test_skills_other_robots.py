"""Other robots seen only through the laser (two teams on one field): a
navigation looks before it leaves, keeps out of the strip a robot at a
station backs off into, and waits for a goal another robot stands on."""
import math

import numpy as np
import pytest

from rll_bt.backend import Pose2D, wrap_angle
from skills.activity import Status
from skills.errors import SkillError
from skills.navigation import Navigate, PoseGoal, StationSideGoal, approach_pose
from skills.navigation.others import BACK_OFF, station_zones, unexplained
from tests.support.skills_scene import STATIONS, Scene


def test_points_at_a_station_stand_for_the_strip_behind_them():
    scene = Scene()
    face = approach_pose(STATIONS["C-BS"], "INPUT", 0.2)           # 20 cm in front of the input face
    far = Pose2D(0.0, 2.5, 0.0)                                      # in the open
    pts = np.array([[face.x, face.y], [far.x, far.y]])
    assert unexplained(scene.ctx, pts).all()
    zone = station_zones(scene.ctx, pts)
    # copies of the point at the station only, out to BACK_OFF further from the face
    out = -np.array([math.cos(face.theta), math.sin(face.theta)])    # the robot there faces the station
    along = (zone - pts[0]) @ out
    assert len(zone) and along.min() > 0.0 and along.max() == pytest.approx(BACK_OFF, abs=1e-6)
    assert np.abs((zone - pts[0]) @ np.array([-out[1], out[0]])).max() < 1e-6
    assert not unexplained(scene.ctx, np.array([[STATIONS["C-BS"].x + 0.17, STATIONS["C-BS"].y]])).any()


def test_a_navigation_looks_before_it_leaves_and_so_sees_the_robot_behind():
    """A robot stood facing away while another came up right behind it, where
    its laser is blind: it turns toward its way before it drives, sees the
    other robot and goes round it, touching nothing."""
    start = Pose2D(0.0, 2.5, math.pi / 2)
    scene = Scene(seed=3, start=start)
    scene.world.add_robot(Pose2D(0.0, 1.95, math.pi / 2))           # 10 cm behind it
    nav = Navigate(scene.ctx, PoseGoal(Pose2D(0.0, 0.8, 0.0)))
    look = scene.ctx.robot.laser_fov / 2.0 - math.pi / 2.0
    nav.start()
    moved_before_looking, looked = [], False
    while not nav.status.done and scene.world.clock.now() < 120.0:
        tp = scene.robot.true_pose
        looked = looked or abs(wrap_angle(-math.pi / 2 - tp.theta)) < look + 0.3   # faces its way (south)
        if not looked:
            moved_before_looking.append(math.hypot(tp.x - start.x, tp.y - start.y))
        nav.poll()
        scene.advance(0.1)
    assert nav.status is Status.SUCCESS, nav.message
    assert max(moved_before_looking) < 0.05
    assert scene.world.collisions == 0


def test_a_goal_another_robot_stands_at_is_waited_for_then_reached():
    scene = Scene(seed=4, start=Pose2D(3.0, 1.0, 0.0))
    other = scene.world.add_robot(approach_pose(STATIONS["C-BS"], "INPUT", 0.27))   # docked at C-BS
    nav = Navigate(scene.ctx, StationSideGoal("C-BS", "INPUT"), max_blocked=6.0)
    assert scene.run(nav, limit=120.0) is Status.FAILURE
    assert nav.error is SkillError.NAVIGATION_FAILED and "another robot stands on the goal" in nav.message
    # it waited clear of the other's way out: where that one stands and backs off to
    tp, op = scene.robot.true_pose, other.true_pose
    way = [op.compose(Pose2D(-d, 0.0, 0.0)) for d in np.linspace(0.0, BACK_OFF, 9)]
    assert min(math.hypot(tp.x - p.x, tp.y - p.y) for p in way) > 2 * 0.225
    assert scene.world.collisions == 0
    other.true_pose = Pose2D(0.0, 4.5, 0.0)                          # it has left
    scene.ctx.costmap.clear_obstacles()
    nav = Navigate(scene.ctx, StationSideGoal("C-BS", "INPUT"))
    assert scene.run(nav, limit=120.0) is Status.SUCCESS, nav.message
    assert scene.world.collisions == 0
