"""The perception mode is a world setting, not a code path in the skills:
a skill context picks the simulator's oracle when the backend reports
detections itself and the camera detectors otherwise."""
import pytest

from rll_bt import rules
from rll_bt.backend import open_backend
from skills.context import SkillContext
from skills.machines import BackendTagSource
from skills.perception.source import CameraPerception

World = pytest.importorskip("backends.sim.world").World


@pytest.mark.parametrize("mode, source", [("oracle", BackendTagSource), ("rendered", CameraPerception)])
def test_skill_context_follows_the_world_setting(mode, source):
    world = World("rcll2016", seed=1, perception=mode)
    try:
        robot = open_backend("sim", world=world, robot=1)
        ctx = SkillContext.create(robot, world.clock, rules.profile(), robot.odometry().pose,
                                  localisation=None)
        assert type(ctx.tags) is source
    finally:
        world.close()
