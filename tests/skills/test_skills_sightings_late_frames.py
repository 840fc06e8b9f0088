"""Tag sightings placed from where the robot was when the frame was taken.

Over a network (a robot's agent in its own process, a loaded host) the
camera's answer and the odometry read after it lie a call or more apart,
while the robot turns: placing the tag from the pose of that later moment
puts the station beside where it stands."""
import math
from collections import deque

import pytest

from rll_bt.backend import Pose2D
from skills.exploration.sightings import SightingCollector
from skills.navigation.laserview import OdometryHistory
from tests.support.skills_scene import STATIONS, Scene


class LateFrames:
    """The robot's detections, handed out ``delay`` seconds late."""

    def __init__(self, robot, clock, delay: float):
        self.robot, self.clock, self.delay = robot, clock, delay
        self.frames: deque = deque()

    def detections(self):
        self.frames.append(self.robot.detections())
        while len(self.frames) > 1 and self.frames[1].stamp <= self.clock.now() - self.delay + 1e-9:
            self.frames.popleft()
        return self.frames[0]


def test_a_late_frame_of_a_turning_robot_places_the_station_where_it_stands():
    # 1.5 m in front of C-CS1's input, turning through the view of its tag
    scene = Scene(seed=2, start=Pose2D(2.06, 4.81, -3 * math.pi / 4 - 0.6), localisation=None)
    scene.ctx.tags = LateFrames(scene.robot, scene.world.clock, delay=0.2)
    seen = SightingCollector(scene.ctx)
    for _ in range(12):                     # at 1 rad/s
        scene.ctx.update()
        scene.robot.drive(0.0, 0.0, 1.0)
        seen.look()
        scene.advance(0.1)
    est = seen.tracker.estimate("C-CS1")
    assert est is not None
    truth = STATIONS["C-CS1"]
    # 0.2 s at 1 rad/s is 0.2 rad: placed from the pose after it, 30 cm off
    assert math.hypot(est.pose.x - truth.x, est.pose.y - truth.y) < 0.03


def test_odometry_history_interpolates_between_readings():
    h = OdometryHistory()
    h.add(1.0, Pose2D(0.0, 0.0, 0.0))
    h.add(1.2, Pose2D(0.2, 0.0, 0.4))
    mid = h.interpolate(1.1)
    assert (mid.x, mid.y, mid.theta) == pytest.approx((0.1, 0.0, 0.2))
    assert h.interpolate(1.2) == Pose2D(0.2, 0.0, 0.4)
    assert h.interpolate(0.9) is None and h.interpolate(1.3) is None
