"""Backing off blind: the laser does not see behind the robot, so a robot
that came to stand there while it looked the other way is found by turning
to look first (in the open; at a station the others keep that strip free)."""
import math

from rll_bt.backend import Pose2D, wrap_angle
from skills.activity import Status
from skills.manipulation.station import back_off_distance
from skills.navigation import approach_pose
from skills.navigation.motions import MoveRelative
from skills.nodes import back_off
from tests.support.skills_scene import STATIONS, Scene

START = Pose2D(0.0, 2.5, math.pi / 2)          # in the open, facing north
BEHIND = Pose2D(0.0, 1.93, 0.0)                 # 12 cm behind it: never in its laser's view


def _scene(other: Pose2D | None):
    scene = Scene(seed=5, start=START)
    if other is not None:
        scene.world.add_robot(other)
    return scene


def test_backing_off_blind_runs_into_a_robot_that_came_up_behind_unseen():
    # the defect the look fixes (a tournament game, seed 1: a robot's recovery
    # back-off in the open ran into its team mate standing behind it)
    scene = _scene(BEHIND)
    move = MoveRelative(scene.ctx, -back_off_distance(scene.ctx, 0.35), speed=0.2, partial=True)
    scene.run(move, limit=30.0)
    assert scene.world.collisions > 0


def test_a_back_off_in_the_open_looks_behind_first_and_stops_short_of_the_robot_there():
    scene = _scene(BEHIND)
    act = back_off(scene.ctx, 0.35)
    headings = []
    act.start()
    while not act.status.done and scene.world.clock.now() < 60.0:
        headings.append(wrap_angle(scene.robot.true_pose.theta - START.theta))
        act.poll()
        scene.advance(0.1)
    assert act.status is Status.SUCCESS, act.message          # a back-off may end short
    assert scene.world.collisions == 0
    assert max(headings) > 1.5 and min(headings) < 0.1      # it turned to look behind, and back
    tp = scene.robot.true_pose
    assert abs(wrap_angle(tp.theta - START.theta)) < 0.05
    assert math.hypot(tp.x - BEHIND.x, tp.y - BEHIND.y) > 2 * 0.225 + 0.03


def test_a_back_off_in_the_open_stops_for_a_robot_that_comes_up_behind_once_it_has_looked():
    # issue 20, seed 1 at cd41937 (970.5 s): the robot looked behind and turned back; meanwhile a robot
    # of the other team came on into the strip behind it, and it backed off blind against where that
    # robot had been when it looked. Here the other robot comes to stand 0.16 m behind it just as it
    # starts to move: it must see it there and stop short
    scene = _scene(None)
    act = back_off(scene.ctx, 0.35)
    other = None
    act.start()
    while not act.status.done and scene.world.clock.now() < 60.0:
        tp = scene.robot.true_pose
        if other is None and math.hypot(tp.x - START.x, tp.y - START.y) > 0.01:
            other = scene.world.add_robot(Pose2D(tp.x, tp.y - 0.62, math.pi / 2))
        act.poll()
        scene.advance(0.1)
    assert other is not None
    assert scene.world.collisions == 0
    assert act.status is Status.SUCCESS, act.message          # a back-off may end short
    tp, op = scene.robot.true_pose, other.true_pose
    assert math.hypot(tp.x - op.x, tp.y - op.y) > 2 * 0.225 + 0.03
    assert abs(wrap_angle(tp.theta - START.theta)) < 0.05


def test_a_back_off_in_the_open_with_nothing_behind_backs_off_the_whole_way():
    scene = _scene(None)
    assert scene.run(back_off(scene.ctx, 0.35), limit=60.0) is Status.SUCCESS
    tp = scene.robot.true_pose
    assert math.hypot(tp.x - START.x, tp.y - START.y) > 0.33
    assert scene.world.collisions == 0


def test_a_back_off_from_a_station_does_not_turn():
    at = approach_pose(STATIONS["C-BS"], "INPUT", 0.05)
    scene = Scene(seed=5, start=at)
    act = back_off(scene.ctx, 0.3)
    assert isinstance(act, MoveRelative)
    act.start()
    turned = 0.0
    while not act.status.done and scene.world.clock.now() < 30.0:
        turned = max(turned, abs(wrap_angle(scene.robot.true_pose.theta - at.theta)))
        act.poll()
        scene.advance(0.1)
    assert act.status is Status.SUCCESS and turned < 0.05
    tp = scene.robot.true_pose
    assert math.hypot(tp.x - at.x, tp.y - at.y) > 0.25
