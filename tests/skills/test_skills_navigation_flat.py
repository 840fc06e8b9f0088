"""Navigate on the flat world: goals around stations and another robot,
failure codes."""
import math

import pytest

from rll_bt.backend import Pose2D
from skills.activity import Status
from skills.errors import SkillError
from skills.navigation import Navigate, PoseGoal, StationSideGoal, ZoneGoal, approach_pose
from tests.support.skills_scene import STATIONS, Scene


@pytest.mark.parametrize("goal", [
    PoseGoal(Pose2D(-4.0, 2.5, 0.0)),
    StationSideGoal("C-CS1", "INPUT"),
    StationSideGoal("C-CS1", "OUTPUT"),
    StationSideGoal("M-RS1", "OUTPUT"),
    ZoneGoal(9),
], ids=lambda g: g.describe())
def test_reaches_goals_around_stations_and_a_parked_robot(goal):
    scene = Scene(seed=1)
    scene.world.add_robot(Pose2D(0.0, 2.5, 0.0))           # another robot in the way
    nav = Navigate(scene.ctx, goal)
    assert scene.run(nav) is Status.SUCCESS, nav.message
    tp = scene.robot.true_pose
    assert math.hypot(tp.x - nav.target.x, tp.y - nav.target.y) < 0.1
    if goal.resolve(scene.ctx)[1]:
        assert abs(math.remainder(tp.theta - nav.target.theta, 2 * math.pi)) < 0.1
    assert scene.world.collisions == 0


def test_station_side_goal_faces_the_face():
    p = approach_pose(Pose2D(1.0, 1.0, 0.0), "INPUT", 0.5)
    assert (p.x, p.y, abs(p.theta)) == pytest.approx((1.0 + 0.175 + 0.5, 1.025, math.pi))
    p = approach_pose(Pose2D(1.0, 1.0, math.pi / 2), "OUTPUT", 0.5)
    assert (p.x, p.y, p.theta) == pytest.approx((1.0 - 0.025, 1.0 - 0.675, math.pi / 2))


def test_replans_around_a_robot_not_in_the_map():
    scene = Scene(seed=2, start=Pose2D(-2.0, 1.2, 0.0))
    scene.world.add_robot(Pose2D(0.0, 1.2, 0.0))            # straight on the line
    nav = Navigate(scene.ctx, PoseGoal(Pose2D(2.0, 1.2, 0.0)))
    assert scene.run(nav) is Status.SUCCESS
    assert nav.replans >= 1 and scene.world.collisions == 0


def test_unknown_station_fails_with_machine_not_found():
    scene = Scene()
    nav = Navigate(scene.ctx, StationSideGoal("C-DS", "INPUT"))
    assert scene.run(nav) is Status.FAILURE and nav.error is SkillError.MACHINE_NOT_FOUND


def test_goal_inside_a_station_is_an_error_not_a_crash():
    scene = Scene()
    bs = STATIONS["C-BS"]
    nav = Navigate(scene.ctx, PoseGoal(Pose2D(bs.x, bs.y, 0.0)))
    assert scene.run(nav) is Status.FAILURE and nav.error is SkillError.NAVIGATION_FAILED
    assert "blocked" in nav.message


def test_a_blocked_corridor_ends_in_navigation_failed_and_the_robot_stops():
    scene = Scene(start=Pose2D(4.5, -0.5, math.pi / 2))
    for x in (3.3, 3.75, 4.2, 4.65, 5.1, 5.55):              # a row of robots closes the insertion area
        scene.world.add_robot(Pose2D(x, 0.25, 0.0))
    nav = Navigate(scene.ctx, PoseGoal(Pose2D(4.5, 3.0, math.pi / 2)), max_blocked=6.0)
    assert scene.run(nav) is Status.FAILURE
    assert nav.error is SkillError.NAVIGATION_FAILED and scene.world.collisions == 0
    assert tuple(scene.robot.cmd) == (0.0, 0.0, 0.0)


def test_timeout_and_cancel_stop_the_robot():
    scene = Scene()
    nav = Navigate(scene.ctx, PoseGoal(Pose2D(-4.0, 2.5, 0.0)), timeout=2.0)
    assert scene.run(nav) is Status.FAILURE and nav.error is SkillError.TIMEOUT
    assert tuple(scene.robot.cmd) == (0.0, 0.0, 0.0)
    nav = Navigate(scene.ctx, PoseGoal(Pose2D(-4.0, 2.5, 0.0))).start()
    for _ in range(10):
        nav.poll()
        scene.advance(0.1)
    assert any(scene.robot.cmd)
    nav.cancel()
    assert nav.status is Status.CANCELLED and nav.error is SkillError.CANCELLED
    assert tuple(scene.robot.cmd) == (0.0, 0.0, 0.0)


def test_kidnapped_robot_either_recovers_or_reports_lost():
    scene = Scene()
    goal = Pose2D(-4.0, 2.5, 0.0)
    nav = Navigate(scene.ctx, PoseGoal(goal)).start()
    nav.poll()
    scene.robot.true_pose = Pose2D(-2.0, 5.4, 2.0)          # carried away: the scans stop fitting
    for _ in range(1200):
        if nav.poll() is not Status.RUNNING:
            break
        scene.advance(0.1)
    tp = scene.robot.true_pose
    if nav.status is Status.SUCCESS:                        # augmented MCL found the pose again
        assert math.hypot(tp.x - goal.x, tp.y - goal.y) < 0.15
    else:
        assert nav.error in (SkillError.LOCALISATION_LOST, SkillError.NAVIGATION_FAILED), nav.message
    assert scene.world.collisions == 0


def test_a_robot_that_does_not_move_counts_as_blocked():
    scene = Scene(localisation=None)
    scene.robot.drive = lambda vx, vy, w: None               # the base ignores commands
    nav = Navigate(scene.ctx, PoseGoal(Pose2D(-4.0, 2.5, 0.0)), max_blocked=5.0)
    assert scene.run(nav, limit=60.0) is Status.FAILURE
    assert nav.error is SkillError.NAVIGATION_FAILED and "does not move" in nav.message


def test_obstacles_remembered_from_an_earlier_way_do_not_fail_a_new_navigation():
    """Robots seen while blocked stay in the costmap for a few seconds; a
    navigation started meanwhile that finds no path with them clears them
    and drives (they may have moved on), instead of failing at once."""
    scene = Scene(seed=2, start=Pose2D(-2.0, 1.2, 0.0))
    wall = [(x, y) for x in (-0.5,) for y in [i * 0.05 - 1.0 for i in range(161)]]   # across the field
    scene.ctx.costmap.add_obstacles(wall, scene.world.clock.now(), 4.0)
    nav = Navigate(scene.ctx, PoseGoal(Pose2D(2.0, 1.2, 0.0)))
    assert scene.run(nav) is Status.SUCCESS, nav.message
    assert nav.cleared == len(wall) and scene.world.collisions == 0
