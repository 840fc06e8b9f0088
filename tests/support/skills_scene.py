"""Shared scenes for the skills tests: a 2016 field in the flat test world
(fast, exact) with six stations, and a helper to run activities.  (A
uniquely named module: every test folder has its own conftest.py.)"""
import math

from rll_bt import rules
from rll_bt.backend import Pose2D
from skills.context import SkillContext
from skills.maps import FieldMap
from skills.testing import FlatWorld

STATIONS = {
    "C-BS": Pose2D(5.0, 0.75, 0.0), "C-CS1": Pose2D(1.0, 3.75, math.pi / 4),
    "C-RS1": Pose2D(3.0, 4.75, 0.0), "M-BS": Pose2D(-5.0, 0.75, math.pi),
    "M-CS1": Pose2D(-1.0, 3.75, 3 * math.pi / 4), "M-RS1": Pose2D(-3.0, 4.75, math.pi),
}


class Scene:
    def __init__(self, seed=0, start=Pose2D(4.5, 2.0, math.pi / 2), localisation="standard",
                 stations_in_map=True):
        self.profile = rules.profile("rcll2016")
        self.world = FlatWorld.from_profile(self.profile, seed=seed)
        self.map = FieldMap.from_profile(self.profile)
        for name, pose in STATIONS.items():
            self.world.add_station(name, pose, self.profile.tag_ids(name))
        self.robot = self.world.add_robot(start)
        self.ctx = SkillContext.create(self.robot, self.world.clock, self.profile, start,
                                       localisation=localisation, seed=seed, field_map=self.map)
        if stations_in_map:
            for name, pose in STATIONS.items():
                self.ctx.machines.set(name, pose)

    def advance(self, dt):
        steps = max(1, round(dt / 0.05))
        for _ in range(steps):
            self.world.step(dt / steps)

    def run(self, activity, limit=300.0):
        return activity.run(0.1, advance=self.advance, limit=limit)

    def pose_error(self):
        est, tp = self.ctx.pose(), self.robot.true_pose
        return math.hypot(est.x - tp.x, est.y - tp.y), abs(math.remainder(est.theta - tp.theta, 2 * math.pi))
