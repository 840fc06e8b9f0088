"""The task trees of ``trees/`` run by a real agent in the PyBullet world.

:class:`SimTaskRig` puts cyan robot 1 at its insertion lane in a 2016 world
with a fixed, roomy layout (stations well apart, so the tests are about the
trees and not about tight corners of a random layout), connects an agent
to a scripted team server over the in-process bus (the server's machine map
is the true station poses, as after a good exploration), and runs tasks in
lockstep: agent step, world step of ``dt`` seconds.
"""
from __future__ import annotations

import math

from backends.sim import FieldLayout, World
from backends.sim.layout import MachinePlacement
from rll_bt import rules
from rll_bt.agent import AgentConfig, RobotAgent
from rll_bt.backend import Pose2D, open_backend
from rll_bt.comm import Bus
from tests.support import TREES
from tests.support.agents import KEY, TEAM, TEAM_REG, TM, ScriptedServer  # noqa: F401 (TM for the tests)

#: cyan stations: zone, x, y, rotation (degrees); magenta mirrors them
ROOMY_2016 = {
    "C-BS": (9, 4.5, 1.0, 0),
    "C-CS1": (6, 3.0, 2.3, 180),
    "C-CS2": (7, 3.0, 3.9, 180),
    "C-RS1": (10, 5.0, 2.6, 90),
    "C-RS2": (3, 1.0, 3.6, 180),
    "C-DS": (4, 1.0, 5.2, 0),
}


def roomy_layout() -> FieldLayout:
    prof = rules.profile("rcll2016")
    machines = {}
    for name, (zone, x, y, rot) in ROOMY_2016.items():
        machines[name] = MachinePlacement(name, zone, rot, Pose2D(x, y, math.radians(rot)))
        twin = "M-" + name[2:]
        tz, trot = prof.mirror_placement(name, zone, rot)
        machines[twin] = MachinePlacement(twin, tz, trot, Pose2D(-x, y, math.radians(trot)))
    return FieldLayout("rcll2016", machines, seed=None)


class SimTaskRig:
    def __init__(self, *, dt: float = 0.05, **robot_options):
        self.world = World("rcll2016", layout=roomy_layout(), perception="oracle")
        self.dt = dt
        self.bus = Bus(self.world.clock)
        self.robot = open_backend("sim", world=self.world, robot=("CYAN", 1), **robot_options)
        start = self.world.robot_pose("CYAN", 1)
        truth = [(n, *self._pose(n)) for n in self.world.machines if n.startswith("C-")]
        self.server = ScriptedServer(self.bus.stream_server("ts", registry=TEAM_REG, key=KEY), machines=truth)
        link = self.bus.stream_client("ts", registry=TEAM_REG, key=KEY)
        self.agent = RobotAgent(AgentConfig(robot_id=1, team_name=TEAM, trees_dir=TREES), clock=self.world.clock,
                                backend=self.robot, link=link, start_pose=start)
        self.next_id = 0
        self.hooks: list = []           # called after every world step with the rig
        self.step(1.0)

    def _pose(self, name: str) -> tuple[float, float, float]:
        p = self.world.station(name).pose
        return p.x, p.y, p.theta

    def step(self, seconds: float) -> None:
        end = self.world.time + seconds
        while self.world.time < end:
            self.round()

    def round(self) -> None:
        self.agent.step()
        self.server.pump()
        self.world.step(self.dt)
        for h in self.hooks:
            h(self)

    def task(self, kind: str, limit: float = 240.0, **fields):
        """Send a task and run until its final result; returns it (:class:`tests.support.agents.Res`)."""
        self.next_id += 1
        tid = self.next_id
        self.server.task(tid, kind, **fields)
        end = self.world.time + limit
        while self.world.time < end:
            self.round()
            final = self.server.final(tid)
            if final is not None:
                return final
        raise AssertionError(f"task {tid} {kind} {fields} did not finish within {limit} s of sim time")

    def held(self):
        return self.world.held_workpiece("CYAN", 1)

    def close(self) -> None:
        self.world.close()


def status(result) -> str:
    return result.status


def error(result) -> str:
    return result.code
