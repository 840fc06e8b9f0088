"""A station face with little room in front of it, and a machine map a few
centimetres off: the approach stops where the robot fits and docks by laser.

The layout is 2016 seed 1's C-RS2 and C-CS2 (C-CS2's corner 1.2 m in front of
C-RS2's input), the map poses those of the rendered-perception game at
f7e0988 (C-RS2 4 cm and 4 degrees off, C-CS2 3 cm off): with them no coarse
stop at 0.40-0.62 m from the face leaves the robot its planning clearance."""
import math

import pytest

from rll_bt import rules
from rll_bt.backend import Pose2D
from skills.activity import Status
from skills.context import SkillContext
from skills.manipulation import ApproachStation, Place
from skills.maps import FieldMap
from skills.navigation.goals import feasible_distance
from skills.testing import FlatWorld

TRUE = {"C-RS2": Pose2D(-0.906, 1.939, -math.pi / 2), "C-CS2": Pose2D(-1.294, 0.762, 3 * math.pi / 4)}
MAPPED = {"C-RS2": Pose2D(-0.939, 1.915, -1.644), "C-CS2": Pose2D(-1.327, 0.760, 2.354)}
START = Pose2D(0.3, 1.2, math.pi)


def scene(mapped, seed=4):
    profile = rules.profile("rcll2016")
    world = FlatWorld.from_profile(profile, seed=seed)
    for name, pose in TRUE.items():
        world.add_station(name, pose, profile.tag_ids(name))
    robot = world.add_robot(START)
    ctx = SkillContext.create(robot, world.clock, profile, START, seed=seed,
                              field_map=FieldMap.from_profile(profile))
    for name, pose in mapped.items():
        ctx.machines.set(name, pose)

    def advance(dt):
        steps = max(1, round(dt / 0.05))
        for _ in range(steps):
            world.step(dt / steps)
    return world, robot, ctx, advance


def test_the_room_before_a_face_reaches_down_to_the_docked_distance():
    _, _, ctx, _ = scene(MAPPED)
    m = ctx.settings.manipulation
    belt = ctx.profile.mps.belt_offset_y
    # with this map the robot fits 0.40 m from the face by the exact distance
    # (0.321 m of clearance, 0.315 m wanted; the 5-cm cells said 0.298 m)
    assert feasible_distance(ctx, MAPPED["C-RS2"], "INPUT", m.coarse_distance, belt) == pytest.approx(0.40)
    # C-CS2 mapped 3 cm closer still: a generic side goal keeps its 0.40 m
    # least standoff and finds no room, the approach's stop comes closer
    c = MAPPED["C-CS2"]
    closer = dict(MAPPED, **{"C-CS2": Pose2D(c.x + 0.021, c.y + 0.021, c.theta)})
    _, _, ctx, _ = scene(closer)
    assert feasible_distance(ctx, closer["C-RS2"], "INPUT", m.coarse_distance, belt) is None
    d = feasible_distance(ctx, closer["C-RS2"], "INPUT", m.coarse_distance, belt, minimum=m.final_distance)
    assert d is not None and m.final_distance < d < 0.40


@pytest.mark.parametrize("spot", ["conveyor", "slide"])
def test_an_approach_with_a_map_a_few_centimetres_off_still_finds_room(spot):
    # seed 6: this map puts the slide's spot 7 cm beside the true one, and the
    # laser's sideways fix after docking takes at most 8 cm (MAX_LATERAL_FIX):
    # with the navigation's and the localiser's few centimetres on top, the
    # robot misses the slide by 8-9 cm on seeds 2, 3, 5, 7, 8 with the 5-cm
    # cells' 0.38 m stop and on seeds 1, 3, 4, 8 with the exact 0.40 m one
    world, robot, ctx, advance = scene(MAPPED, seed=6)
    app = ApproachStation(ctx, Place("C-RS2", "INPUT", spot))
    assert app.run(0.1, advance=advance, limit=120.0) is Status.SUCCESS, app.message
    mps = ctx.profile.mps
    rel = robot.true_pose.relative_to(TRUE["C-RS2"])
    # docked by laser at the true face, in front of the spot, whatever the map said
    assert rel.x - mps.depth / 2 == pytest.approx(ctx.settings.manipulation.final_distance, abs=0.015)
    want = mps.slide_y if spot == "slide" else mps.belt_offset_y
    assert rel.y == pytest.approx(want, abs=0.03)
    assert world.collisions == 0
