"""From a tag seen by a camera to the pose of its machine in the field frame.

Chain: tag pose in the camera optical frame (solvePnP) -> camera extrinsics
-> robot pose in the field -> tag position and face normal in the field ->
machine centre through the tag's known mounting (rules.geometry: centred
below the belt on the input face at machine x = +depth/2 with its face
pointing along +x, or on the output face at x = -depth/2 pointing along -x).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import cv2
import numpy as np

from rll_bt.backend import CameraExtrinsics, Pose2D, TagDetection, wrap_angle
from rll_bt.rules import MpsGeometry


@dataclass(frozen=True)
class TagInField:
    tag_id: int
    position: tuple[float, float, float]   # tag centre, field frame, metres
    normal_yaw: float                       # direction the marker face points to, radians
    distance: float                         # camera to tag, metres
    view_angle: float                       # angle between the face normal and the line of sight


def tag_in_robot(det: TagDetection, extrinsics: CameraExtrinsics) -> tuple[np.ndarray, np.ndarray]:
    """(tag centre, face normal) in the robot frame."""
    r_cam = extrinsics.rotation()
    r_tag, _ = cv2.Rodrigues(np.asarray(det.rvec, dtype=np.float64))
    p = r_cam @ np.asarray(det.tvec, dtype=np.float64) + np.asarray(extrinsics.position)
    n = r_cam @ r_tag[:, 2]
    return p, n


def tag_in_field(det: TagDetection, extrinsics: CameraExtrinsics, robot: Pose2D) -> TagInField:
    p, n = tag_in_robot(det, extrinsics)
    c, s = math.cos(robot.theta), math.sin(robot.theta)
    x = robot.x + c * p[0] - s * p[1]
    y = robot.y + s * p[0] + c * p[1]
    nx, ny = c * n[0] - s * n[1], s * n[0] + c * n[1]
    t = np.asarray(det.tvec, dtype=np.float64)
    dist = float(np.linalg.norm(t))
    r_tag, _ = cv2.Rodrigues(np.asarray(det.rvec, dtype=np.float64))
    view = float(math.acos(max(-1.0, min(1.0, -float(r_tag[:, 2] @ t) / max(dist, 1e-9)))))
    return TagInField(det.tag_id, (float(x), float(y), float(p[2])), math.atan2(ny, nx), dist, view)


def machine_pose_from_tag(tag: TagInField, side: str, mps: MpsGeometry) -> Pose2D:
    """Centre and rotation of the machine whose ``side`` ("INPUT"/"OUTPUT") carries the tag.

    The machine rotation is the direction of its local x axis (output to
    input): the input tag faces +x, the output tag faces -x.
    """
    if side == "INPUT":
        theta = tag.normal_yaw
        local = (mps.depth / 2.0, mps.belt_offset_y)
    elif side == "OUTPUT":
        theta = wrap_angle(tag.normal_yaw + math.pi)
        local = (-mps.depth / 2.0, mps.belt_offset_y)
    else:
        raise ValueError(f"side must be INPUT or OUTPUT, not {side!r}")
    c, s = math.cos(theta), math.sin(theta)
    x = tag.position[0] - (c * local[0] - s * local[1])
    y = tag.position[1] - (s * local[0] + c * local[1])
    return Pose2D(x, y, wrap_angle(theta))


def tag_pose_on_machine(machine: Pose2D, side: str, mps: MpsGeometry) -> tuple[Pose2D, float]:
    """(tag centre with its face-normal yaw, tag height) for a machine pose: the
    inverse of :func:`machine_pose_from_tag`, used by simulators and tests."""
    if side == "INPUT":
        local = Pose2D(mps.depth / 2.0, mps.belt_offset_y, 0.0)
    elif side == "OUTPUT":
        local = Pose2D(-mps.depth / 2.0, mps.belt_offset_y, math.pi)
    else:
        raise ValueError(f"side must be INPUT or OUTPUT, not {side!r}")
    return machine.compose(local), mps.tag_centre_height

