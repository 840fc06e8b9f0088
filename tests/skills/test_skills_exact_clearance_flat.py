"""Whether the robot fits at a pose is decided by the exact distance to the
map's walls and stations, not by 5-cm cells: a window in front of a face a
few centimetres wider than the robot needs is open wherever the cell
borders fall, and a narrower one stays shut.

The scene: a station facing +x with a wall parallel to its input face,
``gap`` metres out.  The robot needs ``standing_clearance`` (0.315 m) from
both, so the window exists when the gap is at least 0.63 m.  A cell's
value holds only at its centre, and the cells erred both ways: with a cell
border 0.335 m from the face every stop of 0.30-0.40 m took the value of a
centre 0.31 m from the face or 0.305 m from the wall (the window of
0.315-0.35 m shut), with one on the face a stop 0.305 m from the wall or
0.30 m from the face took one 0.325 m away (let through)."""
import pytest

from rll_bt import rules
from rll_bt.backend import Pose2D
from skills.activity import Status
from skills.context import SkillContext
from skills.errors import SkillError
from skills.maps import FieldMap
from skills.navigation import Navigate, PoseGoal, approach_pose
from skills.navigation.goals import feasible_distance, standing_clearance
from skills.testing import FlatWorld

PROFILE = rules.profile("rcll2016")
START = Pose2D(-3.0, 2.0, 0.0)


def scene(gap: float, border: float):
    """A station whose input face lies ``border`` metres before a cell
    border of the costmap's grid, and a wall ``gap`` metres from that face."""
    field = FieldMap.from_profile(PROFILE)
    world = FlatWorld.from_profile(PROFILE, seed=1)
    robot = world.add_robot(START)
    ctx = SkillContext.create(robot, world.clock, PROFILE, START, seed=1, field_map=field)
    res = ctx.settings.costmap_resolution
    mps = PROFILE.mps
    x0 = field.grid_spec(res).x0
    face = x0 + round((1.0 - x0) / res) * res - border      # near x = 1
    pose = Pose2D(face - mps.depth / 2.0, 4.0, 0.0)
    ctx.machines.set("C-BS", pose)
    wall = face + gap
    field.add_obstacle([(wall, 3.0), (wall + 0.1, 3.0), (wall + 0.1, 5.0), (wall, 5.0)], "wall")
    return ctx, pose


@pytest.mark.parametrize("border", [0.335, 0.0, 0.01, 0.02, 0.03, 0.04])
def test_a_window_a_few_centimetres_wide_is_open_wherever_the_cells_fall(border):
    ctx, pose = scene(0.665, border)
    belt = PROFILE.mps.belt_offset_y
    assert standing_clearance(ctx) == pytest.approx(0.315)
    # the farthest stop of 0.40, 0.38, ... that keeps 0.315 m from both: 0.34 m
    # (0.325 m from the wall); by the cells none at border 0.335, 0.36 m at 0.01
    # and 0.02 (0.305 m from the wall), none at 0.03, 0.32 m at 0.04
    assert feasible_distance(ctx, pose, "INPUT", 0.40, belt, minimum=0.30) == pytest.approx(0.34)


@pytest.mark.parametrize("border", [0.335, 0.0, 0.02])
def test_a_window_narrower_than_the_robot_needs_stays_shut(border):
    ctx, pose = scene(0.62, border)
    belt = PROFILE.mps.belt_offset_y
    assert feasible_distance(ctx, pose, "INPUT", 0.40, belt, minimum=0.20) is None


def _navigating(ctx, pose, distance):
    """A navigation started toward ``distance`` m in front of the station's input, and its goal."""
    goal = approach_pose(pose, "INPUT", distance, PROFILE.mps.belt_offset_y)
    nav = Navigate(ctx, PoseGoal(goal))
    nav.start()
    return nav, goal


def test_a_navigation_goal_that_fits_by_the_exact_distance_is_kept():
    ctx, pose = scene(0.665, 0.335)
    nav, goal = _navigating(ctx, pose, 0.34)
    # it fits where it is; the cells moved it 0.45 m, beside the station
    assert (nav.target.x, nav.target.y) == (goal.x, goal.y) and nav.adjusted == 0.0
    nav.cancel()


def test_a_navigation_goal_that_does_not_fit_moves_to_the_nearest_spot_that_does():
    ctx, pose = scene(0.665, 0.0)
    # 0.015 m short of the face's clearance (the cells let it stand there)
    nav, goal = _navigating(ctx, pose, 0.30)
    moved = nav.target.relative_to(pose).x - PROFILE.mps.depth / 2.0
    # along the face's normal, by about what it lacked (and 1 cm more), no farther
    assert 0.30 + 0.02 <= moved <= 0.30 + 0.035 and nav.adjusted < 0.04
    assert abs(nav.target.y - goal.y) < 0.011
    clear = ctx.map.clearance(nav.target.x, nav.target.y)[0]
    assert clear >= standing_clearance(ctx) + 0.01
    nav.cancel()


def test_a_goal_in_a_gap_too_narrow_for_the_robot_is_refused():
    ctx, pose = scene(0.50, 0.0)
    nav, _ = _navigating(ctx, pose, 0.25)
    assert nav.status is Status.FAILURE and nav.error is SkillError.NAVIGATION_FAILED
    assert "no room for the robot" in nav.message
