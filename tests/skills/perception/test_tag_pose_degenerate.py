"""A tag pose that cannot be had (corners on one point or a line, a pose or a
projection that is not finite) is no detection, not an exception: in a
rendered game a NaN tag pose once raised out of the exploration tree
("cannot convert float NaN to integer" in tower_region)."""
from __future__ import annotations

import math

import numpy as np
import pytest

from rll_bt import rules
from rll_bt.backend import CameraIntrinsics, TagDetection
from skills.perception.light.region import tower_region
from skills.perception.tags.detector import TagDetector

PROFILE = rules.profile("rcll2016")
K = CameraIntrinsics.from_fov(640, 480, 1.0)
TAG = PROFILE.tag_ids("C-RS1")[0]


@pytest.mark.parametrize("tvec, rvec", [
    ((math.nan, 0.0, 1.5), (0.0, math.pi, 0.0)),
    ((0.0, 0.0, 1.5), (math.inf, 0.0, 0.0)),
])
def test_a_tag_pose_that_is_not_finite_gives_no_tower_region(tvec, rvec):
    assert tower_region(TagDetection(TAG, tvec, rvec), "INPUT", PROFILE.mps, K) is None


def test_a_finite_tag_pose_in_front_gives_a_region_inside_the_image():
    region, height = tower_region(TagDetection(TAG, (0.0, 0.1, 1.5), (0.0, math.pi, 0.0)), "INPUT", PROFILE.mps, K)
    x, y, w, h = region
    assert x >= 0 and y >= 0 and x + w <= K.width and y + h <= K.height and height > 0


@pytest.mark.parametrize("corners", [
    [[100, 100]] * 4,                                   # one point
    [[100, 100], [101, 100], [102, 100], [103, 100]],   # on a line
])
def test_degenerate_corners_give_no_pose(corners):
    det = TagDetector(PROFILE.tag_size)
    assert det._solve(np.asarray(corners, np.float64), K.matrix, np.zeros(5), None) is None
