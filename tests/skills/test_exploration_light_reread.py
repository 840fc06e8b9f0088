"""ExploreZone (2016) reads an unsure light again rather than leave with it:
after a moment, then from a second view sideways.  The simulator's tags are
real; the tower is read by a detector whose answers the test controls: from
the first place the robot stands looking at it after its first drive (a
glare) it reads the wrong state, unsure, and right from anywhere else; like a
camera in motion it reads nothing while the robot drives.  One sure view does
not settle a light: the robot takes a second one from another place."""
import math

import pytest

from rll_bt.backend import Detections, LightDetection, Pose2D, open_backend
from skills.activity import Status
from skills.context import SkillContext
from skills.exploration import ExploreZone
from skills.exploration.light_views import VIEW_CONFIDENCE

sim = pytest.importorskip("backends.sim")

STATION = "C-CS1"


def probs(state, p):
    return tuple(p if s == state else (1.0 - p) / 7 for s in range(8))


class GlareReader:
    """The world's tags, and lights read as the test says (see the module doc)."""

    def __init__(self, source, world, wrong: int, right: int):
        self.source, self.world = source, world
        self.wrong, self.right = wrong, right
        self.glare_at: Pose2D | None = None
        self.last, self.driven = None, False
        self.answers: list[tuple[int, float]] = []

    def detections(self):
        dets = self.source.detections()
        if dets is None:
            return None
        here = self.world.robot_pose("CYAN", 1)
        moving = self.last is not None and math.hypot(here.x - self.last.x, here.y - self.last.y) > 0.01
        self.last = here
        self.driven = self.driven or moving
        lights = []
        for light in dets.lights:
            owner = self.world.profile.machine_for_tag(light.tag_id) if light.tag_id is not None else None
            if moving or not self.driven or owner is None or owner[0] != STATION:
                continue                                # (other stations' towers: not read)
            if self.glare_at is None:
                self.glare_at = here
            glare = math.hypot(here.x - self.glare_at.x, here.y - self.glare_at.y) < 0.3
            state, p = (self.wrong, 0.8) if glare else (self.right, 0.995)
            self.answers.append((state, p))
            lights.append(LightDetection(light.box, state, p, probs(state, p), light.camera, light.tag_id))
        return Detections(dets.stamp, dets.tags, tuple(lights), dets.extrinsics)


def test_an_unsure_light_is_read_again_after_a_moment_then_from_a_view_sideways():
    world = sim.World("rcll2016", seed=3)
    world.set_lights(STATION, green="ON", yellow="ON")
    right = world.visible_light_code(STATION)
    wrong = right ^ 4                                   # red seen lit: another type
    bot = open_backend("sim", world=world, robot=("CYAN", 1))
    ctx = SkillContext.create(bot, world.clock, world.profile, world.robot_pose("CYAN", 1),
                              localisation="standard", seed=3)
    ctx.tags = reader = GlareReader(ctx.tags, world, wrong, right)
    sent = []
    ctx.machines.subscribe(sent.append)
    st = world.stations[STATION].pose
    x, y = 2.22, 4.97                                   # a place that sees the tower of seed 3's C-CS1
    ex = ExploreZone(ctx, world.stations[STATION].zone, max_viewpoints=1,
                     viewpoints=[Pose2D(x, y, math.atan2(st.y - y, st.x - x))])
    assert ex.run(0.1, advance=world.step, limit=150.0) is Status.SUCCESS, ex.message
    assert world.collision_count == 0
    look = reader.glare_at
    assert (wrong, 0.8) in reader.answers and (right, 0.995) in reader.answers
    views = ex.collector.views
    first = views.verdict(STATION, 1)
    assert first.state == wrong and first.confidence < VIEW_CONFIDENCE   # the glare: read, unsure
    assert (STATION, 1) in ex.lingered                  # read again after a moment, still wrong
    assert ex.sideways.get(STATION) == 2                # then from a view sideways, sure, and another
    assert ex.collector.light_state(STATION) == right   # which settles it (two sure views)
    robot = world.robot_pose("CYAN", 1)
    assert 0.3 < math.hypot(robot.x - look.x, robot.y - look.y) < 1.2
    told = [(o.light_state, o.light_confidence) for o in sent if o.machine == STATION and o.light_view]
    assert all(c < VIEW_CONFIDENCE for s, c in told if s == wrong)   # the wrong one only ever as unsure
    assert (right, pytest.approx(0.995, abs=1e-6)) in told
