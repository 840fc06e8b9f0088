"""A station's tag as the robot sees it, on the floor plane.

From a :class:`~rll_bt.backend.TagDetection` (camera optical frame) and
the camera extrinsics, through perception's ``tag_in_robot``, to the tag's
2D pose in the robot frame: its centre and the yaw its face points to.
"""
from __future__ import annotations

import math

from rll_bt.backend import Detections, Pose2D

from ..perception.tags import tag_in_robot


def tag_pose_in_robot(detections: Detections, tag_id: int) -> Pose2D | None:
    """The tag ``tag_id`` as (x, y, normal yaw) in the robot frame, or None
    when it is not in ``detections``."""
    for det in detections.tags:
        if det.tag_id == tag_id:
            p, n = tag_in_robot(det, detections.extrinsics)
            return Pose2D(float(p[0]), float(p[1]), math.atan2(float(n[1]), float(n[0])))
    return None
