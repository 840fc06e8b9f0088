"""A tower is read only where it shows whole.  The camera (0.57 m) is lower
than the cabinet's top and the tower's lowest lamp stands just above it,
near the output face: from off the input face, or from nearer than about
1.5 m, the station hides that lamp or the tower leaves the image, and a
reader reads the hidden lamp as dark, sure of it (in the rendered game of
seed 1 a cap station's green, yellow and red read from its input side as
yellow and red at 0.999).  The perception skips those towers, and the
exploration reads a tower from places off its output face."""
from __future__ import annotations

import math

import cv2
import numpy as np
import pytest

from rll_bt import rules
from rll_bt.backend import CameraIntrinsics, Pose2D, TagDetection
from skills.exploration.light_views import light_viewpoints
from skills.perception.light.region import camera_in_machine_frame, lowest_lamp_visible, tower_readable, tower_region

PROFILE = rules.profile("rcll2016")
MPS = PROFILE.mps
K = CameraIntrinsics.from_fov(320, 240, PROFILE.robot.camera_hfov)
HEIGHT = PROFILE.robot.camera_mount[2]


def seen_from(side: str, x: float, y: float) -> TagDetection:
    """The tag on ``side`` as a level camera at (x, y, HEIGHT) of the machine's
    frame, looking at the tower, sees it (exact pose)."""
    sign = 1.0 if side == "INPUT" else -1.0
    cam = np.array([x, y, HEIGHT])
    h = math.atan2(MPS.tower_y - y, MPS.tower_x - x)
    # optical axes in the machine frame: x right, y down, z forward
    r_cm = np.array([[math.sin(h), -math.cos(h), 0.0], [0.0, 0.0, -1.0], [math.cos(h), math.sin(h), 0.0]])
    tag_axes = np.array([[0.0, 0.0, sign], [sign, 0.0, 0.0], [0.0, 1.0, 0.0]])   # columns: tag x, y, z
    tag = np.array([sign * MPS.depth / 2.0, MPS.belt_offset_y, MPS.tag_centre_height])
    rvec, _ = cv2.Rodrigues(r_cm @ tag_axes)
    return TagDetection(PROFILE.tag_ids("C-CS1")[0 if side == "INPUT" else 1], tuple(r_cm @ (tag - cam)),
                        tuple(rvec.ravel()))


@pytest.mark.parametrize("side, x, y", [("OUTPUT", -2.0, -0.3), ("INPUT", 1.8, 0.6)])
def test_the_camera_is_where_the_tag_pose_says(side, x, y):
    assert camera_in_machine_frame(seen_from(side, x, y), side, MPS) == pytest.approx([x, y, HEIGHT], abs=1e-9)


def test_the_lowest_lamp_shows_off_the_output_face_from_far_enough_only():
    out = [lowest_lamp_visible((-MPS.depth / 2 - d, MPS.tower_y, HEIGHT), MPS) for d in (0.8, 1.2, 1.6, 2.0, 3.0)]
    assert out == sorted(out) and out[0] < 0.35 < out[2] and out[-1] > 0.8       # farther: more of it
    assert lowest_lamp_visible((MPS.depth / 2 + 2.5, MPS.tower_y, HEIGHT), MPS) == 0.0   # input side: none
    assert lowest_lamp_visible((-2.0, 0.0, 1.2), MPS) == 1.0                   # a camera above the top: all


def test_a_tower_is_readable_off_the_output_face_not_off_the_input_face_nor_too_near():
    assert tower_readable(seen_from("OUTPUT", -2.0, -0.3), "OUTPUT", MPS, K, HEIGHT)
    assert tower_region(seen_from("INPUT", 2.0, 0.0), "INPUT", MPS, K) is not None   # in view, but hidden
    assert not tower_readable(seen_from("INPUT", 2.0, 0.0), "INPUT", MPS, K, HEIGHT)
    assert not tower_readable(seen_from("OUTPUT", -0.9, -0.2), "OUTPUT", MPS, K, HEIGHT)   # top out of the image


def test_light_viewpoints_are_off_the_output_face_facing_the_tower_best_first():
    station = Pose2D(-1.3, 0.76, 3 * math.pi / 4)
    places = light_viewpoints(station, PROFILE)
    assert [s for s, _ in places] == sorted((s for s, _ in places), reverse=True) and places[0][0] > 0.7
    c, s = math.cos(station.theta), math.sin(station.theta)
    tower = (station.x + c * MPS.tower_x - s * MPS.tower_y, station.y + s * MPS.tower_x + c * MPS.tower_y)
    for _seen, p in places:
        assert (p.x - station.x) * c + (p.y - station.y) * s < -MPS.depth / 2 - 0.5   # off the output face
        assert abs(math.remainder(p.theta - math.atan2(tower[1] - p.y, tower[0] - p.x), 2 * math.pi)) < 1e-9
