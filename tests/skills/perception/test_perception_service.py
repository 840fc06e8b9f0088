"""The perception service and its tree nodes, fed by a scripted detections
source; and the choice of source by a setting."""
import math

import cv2
import numpy as np
import pytest
from py_trees.common import Status

from rll_bt import rules
from rll_bt.backend import (
    Backend,
    CameraExtrinsics,
    Capability,
    Detections,
    LightDetection,
    Odometry,
    Pose2D,
    TagDetection,
)
from rll_bt.tree import BB, RunContext
from skills.perception.nodes import DetectMachine, Perceive, ReadLight
from skills.perception.service import PerceptionService
from skills.perception.source import CameraPerception, OracleSource, make_tag_source

PROFILE = rules.profile("rcll2016")
EXT = CameraExtrinsics(position=(0.2, 0.0, 0.57))
MACHINE = Pose2D(3.0, 2.4, math.pi)     # C-RS1 facing -x: its input tag faces the robot at x < 3
ROBOT = Pose2D(1.6, 2.425, 0.0)


def input_tag_seen_from(robot: Pose2D, machine: Pose2D):
    """The exact camera-frame pose of the machine's input tag."""
    mps = PROFILE.mps
    c, s = math.cos(machine.theta), math.sin(machine.theta)
    lx, ly = mps.depth / 2, mps.belt_offset_y
    centre = np.array([machine.x + c * lx - s * ly, machine.y + s * lx + c * ly, mps.tag_centre_height])
    z = np.array([c, s, 0.0])
    y = np.array([0.0, 0.0, 1.0])
    frame = np.column_stack([np.cross(y, z), y, z])
    cr, sr = math.cos(robot.theta), math.sin(robot.theta)
    r_robot = np.array([[cr, -sr, 0], [sr, cr, 0], [0, 0, 1.0]])
    r_cam = r_robot @ EXT.rotation()
    eye = np.array([robot.x, robot.y, 0.0]) + r_robot @ np.array(EXT.position)
    t = r_cam.T @ (centre - eye)
    rvec, _ = cv2.Rodrigues(r_cam.T @ frame)
    return TagDetection(PROFILE.tag_ids("C-RS1")[0], tuple(t), tuple(rvec.ravel()))


class ScriptedSource:
    def __init__(self, frames):
        self.frames = list(frames)
        self.i = -1

    def detections(self):
        self.i = min(self.i + 1, len(self.frames) - 1)
        return self.frames[self.i]


def frames(states, dt=0.1, tag=True):
    tag_det = input_tag_seen_from(ROBOT, MACHINE)
    out = []
    for i, st in enumerate(states):
        lights = (LightDetection((300, 100, 10, 40), st, 1.0, tag_id=tag_det.tag_id if tag else None),)
        out.append(Detections(i * dt, (tag_det,) if tag else (), lights, EXT))
    return out


def test_service_tracks_the_station_and_reads_its_lights():
    seen = []
    blink = [2 | (1 if (i // 2.5) % 2 == 0 else 0) for i in range(25)]   # yellow on, green 2 Hz
    svc = PerceptionService(ScriptedSource(frames(blink)), PROFILE, lambda: ROBOT, seen.append)
    for _ in range(25):
        svc.update()
    assert svc.update() == set()                          # the same frame again: nothing new
    r = svc.report("C-RS1")
    assert r.pose.distance_to(MACHINE) < 0.01 and r.zone == PROFILE.zone_at(MACHINE.x, MACHINE.y)
    assert r.rotation_deg == 180 and r.confidence > 0.5
    assert r.pattern.as_dict() == {"green": "BLINK", "yellow": "ON", "red": "OFF"}
    assert r.light_state is None
    assert seen and seen[-1].machine == "C-RS1" and seen[-1].side == "INPUT" and seen[-1].zone == r.zone


def ctx_with(svc):
    return RunContext(services={"perception": svc})


def test_detect_machine_node_writes_the_estimate():
    svc = PerceptionService(ScriptedSource(frames([5] * 10)), PROFILE, lambda: ROBOT)
    ctx = ctx_with(svc)
    node = DetectMachine.make(ctx, machine="C-RS1", min_confidence=0.5, timeout=5.0, found=BB("m"),
                              pose=BB("pose"), zone=BB("zone"), rotation=BB("rot"))
    statuses = [next(node.tick()).status for _ in range(6)]
    assert statuses[-1] == Status.SUCCESS
    bb = ctx.blackboard
    assert bb.get("/m") == "C-RS1" and bb.get("/rot") == 180
    assert bb.get("/pose").distance_to(MACHINE) < 0.01


def test_detect_machine_times_out_with_machine_not_found():
    from rll_bt.clock import SimClock
    clock = SimClock()
    svc = PerceptionService(ScriptedSource([Detections(0.0, (), (), EXT)]), PROFILE, lambda: ROBOT)
    ctx = RunContext(clock=clock, services={"perception": svc})
    node = DetectMachine.make(ctx, machine="C-BS", timeout=1.0)
    assert next(node.tick()).status == Status.RUNNING
    clock.advance(1.5)
    assert next(node.tick()).status == Status.FAILURE
    assert ctx.blackboard.get("/error/code") == "MACHINE_NOT_FOUND"


def test_read_light_and_perceive_nodes():
    from rll_bt.clock import SimClock
    clock = SimClock()
    svc = PerceptionService(ScriptedSource(frames([5] * 30)), PROFILE, lambda: ROBOT)
    ctx = RunContext(clock=clock, services={"perception": svc})
    read = ReadLight.make(ctx, machine="C-RS1", pattern=BB("pattern"), state=BB("state"))
    status = None
    for _ in range(30):
        status = next(read.tick()).status
        clock.advance(0.1)
        if status != Status.RUNNING:
            break
    assert status == Status.SUCCESS
    assert ctx.blackboard.get("/state") == 5
    assert ctx.blackboard.get("/pattern") == {"green": "ON", "yellow": "OFF", "red": "ON"}
    perceive = Perceive.make(ctx, duration=0.3, machines=BB("seen"))
    assert next(perceive.tick()).status == Status.RUNNING
    clock.advance(0.5)
    assert next(perceive.tick()).status == Status.SUCCESS
    assert ctx.blackboard.get("/seen") == ["C-RS1"]


class FakeBackend(Backend):
    name = "fake"

    def __init__(self, caps):
        self._caps = caps

    @property
    def capabilities(self):
        return self._caps

    def drive(self, vx, vy, omega):
        pass

    def odometry(self):
        return Odometry(0.0, Pose2D())

    def detections(self, camera="front"):
        return Detections(1.0)


def test_the_source_is_a_setting():
    oracle = FakeBackend(Capability.CAMERA | Capability.DETECTIONS)
    camera_only = FakeBackend(Capability.CAMERA)
    assert isinstance(make_tag_source(oracle, PROFILE), OracleSource)
    assert isinstance(make_tag_source(oracle, PROFILE, "camera"), CameraPerception)
    assert isinstance(make_tag_source(camera_only, PROFILE), CameraPerception)
    with pytest.raises(Exception, match="DETECTIONS"):
        make_tag_source(camera_only, PROFILE, "oracle")
    with pytest.raises(ValueError, match="perception mode"):
        make_tag_source(oracle, PROFILE, "magic")
    assert make_tag_source(oracle, PROFILE).detections().stamp == 1.0
    assert CameraPerception(camera_only, PROFILE).detections() is None      # no camera: nothing, no crash
