"""Tag pipeline on synthetic camera images with known truth.

The images are made independently of the pipeline: the marker's 3D corners
are placed from a machine pose through the rulebook mounting, projected with
cv2.projectPoints into a pinhole camera on a robot, and the marker bitmap is
warped there."""
import math

import cv2
import numpy as np
import pytest

from rll_bt import rules
from rll_bt.backend import CameraExtrinsics, CameraIntrinsics, Pose2D
from skills.perception.tags import MachineTracker, TagDetector, machine_pose_from_tag, tag_in_field


def world_to_camera(robot: Pose2D, ext: CameraExtrinsics):
    """rvec, tvec mapping field points into the optical frame."""
    c, s = math.cos(robot.theta), math.sin(robot.theta)
    r_robot = np.array([[c, -s, 0], [s, c, 0], [0, 0, 1.0]])
    r_cam = r_robot @ ext.rotation()                               # optical -> field
    p_cam = np.array([robot.x, robot.y, 0.0]) + r_robot @ np.array(ext.position)
    r_wc = r_cam.T
    t_wc = -r_wc @ p_cam
    return cv2.Rodrigues(r_wc)[0], t_wc


def marker_corners_field(machine: Pose2D, side: str, profile):
    """TL, TR, BR, BL corners of the tag as seen from the front, in the field frame."""
    mps = profile.mps
    sx = 1.0 if side == "INPUT" else -1.0
    cx, cy = sx * mps.depth / 2.0, mps.belt_offset_y
    h = profile.tag_size / 2.0
    zc = mps.tag_centre_height
    # a viewer in front of the face looks along -normal = (-sx, 0); their right-hand
    # side is then (0, sx) in the machine frame, and the marker's right is theirs
    pts_local = [(cx, cy - sx * h, zc + h), (cx, cy + sx * h, zc + h),
                 (cx, cy + sx * h, zc - h), (cx, cy - sx * h, zc - h)]
    c, s = math.cos(machine.theta), math.sin(machine.theta)
    return np.array([[machine.x + c * x - s * y, machine.y + s * x + c * y, z] for x, y, z in pts_local])


def synth_image(profile, name, machine, side, robot, ext, k, rng):
    tag_id = profile.tag_ids(name)[0 if side == "INPUT" else 1]
    dictionary = cv2.aruco.getPredefinedDictionary(cv2.aruco.DICT_ARUCO_ORIGINAL)
    bits = cv2.aruco.generateImageMarker(dictionary, tag_id, 140)
    marker = cv2.copyMakeBorder(bits, 20, 20, 20, 20, cv2.BORDER_CONSTANT, value=255)  # white margin
    n = bits.shape[0]
    src = np.float32([[20, 20], [20 + n, 20], [20 + n, 20 + n], [20, 20 + n]])
    corners = marker_corners_field(machine, side, profile)
    rvec, tvec = world_to_camera(robot, ext)
    img_pts, _ = cv2.projectPoints(corners, rvec, tvec, k.matrix, np.zeros(5))
    dst = img_pts.reshape(4, 2).astype(np.float32)
    h = cv2.getPerspectiveTransform(src, dst)
    canvas = np.full((k.height, k.width), 255, np.uint8)
    warped = cv2.warpPerspective(marker, h, (k.width, k.height), dst=canvas.copy(),
                                 borderMode=cv2.BORDER_TRANSPARENT)
    noisy = np.clip(warped.astype(np.float32) * 0.8 + 30 + rng.normal(0, 3, warped.shape), 0, 255)
    return cv2.cvtColor(noisy.astype(np.uint8), cv2.COLOR_GRAY2BGR), tag_id


K = CameraIntrinsics.from_fov(640, 480, 1.08)
EXT = CameraExtrinsics(position=(0.2, 0.0, 0.57), pitch=0.0)
UP = EXT.rotation().T @ np.array([0.0, 0.0, 1.0])


@pytest.mark.parametrize("profile_name", rules.PROFILES)
@pytest.mark.parametrize("side", ["INPUT", "OUTPUT"])
def test_machine_pose_from_synthetic_views(profile_name, side):
    p = rules.profile(profile_name)
    rng = np.random.default_rng(7)
    name = "C-RS1"
    machine = Pose2D(3.4, 2.6, math.radians(135))
    normal = machine.theta if side == "INPUT" else machine.theta + math.pi
    detector = TagDetector(p.tag_size, valid_ids=p.all_tag_ids)
    tracker = MachineTracker(p)
    errors = []
    for _ in range(12):
        dist = rng.uniform(0.8, 2.2)
        off = rng.uniform(-0.5, 0.5)
        # robot in front of the face, looking at it
        tx = machine.x + math.cos(normal) * (0.175 + dist)
        ty = machine.y + math.sin(normal) * (0.175 + dist)
        lat = off * dist
        tx += -math.sin(normal) * lat
        ty += math.cos(normal) * lat
        robot = Pose2D(tx, ty, math.atan2(machine.y - ty, machine.x - tx) + rng.normal(0, 0.05))
        img, tag_id = synth_image(p, name, machine, side, robot, EXT, K, rng)
        dets = detector.detect(img, K, up=UP)
        assert [d.tag_id for d in dets] == [tag_id]
        one = machine_pose_from_tag(tag_in_field(dets[0], EXT, robot), side, p.mps)
        errors.append(one.distance_to(machine))
        assert tracker.add(dets[0], EXT, robot) == name
    assert np.median(errors) < 0.05
    est = tracker.estimate(name)
    assert est.pose.distance_to(machine) < 0.04
    assert abs(math.degrees((est.pose.theta - machine.theta + math.pi) % (2 * math.pi) - math.pi)) < 3
    assert est.zone == p.zone_at(machine.x, machine.y)
    assert est.rotation_deg == 135
    assert est.confidence > 0.5 and est.sides == {side}


def test_unknown_tags_are_ignored():
    p = rules.profile("rcll2016")
    rng = np.random.default_rng(1)
    machine = Pose2D(3.0, 2.4, 0.0)
    robot = Pose2D(4.5, 2.425, math.pi)
    img, tag_id = synth_image(p, "C-RS1", machine, "INPUT", robot, EXT, K, rng)
    assert TagDetector(p.tag_size, valid_ids={999}).detect(img, K) == []
    assert TagDetector(p.tag_size).detect(np.zeros((480, 640, 3), np.uint8), K) == []


def test_outlier_gated_then_restart():
    p = rules.profile("rcll2016")
    tracker = MachineTracker(p, restart_after=3)
    rng = np.random.default_rng(3)
    machine = Pose2D(3.0, 2.4, 0.0)
    robot = Pose2D(4.6, 2.425, math.pi)
    img, _ = synth_image(p, "C-RS1", machine, "INPUT", robot, EXT, K, rng)
    det = TagDetector(p.tag_size).detect(img, K)[0]
    for _ in range(5):
        assert tracker.add(det, EXT, robot) == "C-RS1"
    moved = Pose2D(robot.x, robot.y + 1.0, robot.theta)     # a wrong robot pose: 1 m off
    assert tracker.add(det, EXT, moved) is None              # gated
    assert tracker.add(det, EXT, moved) is None
    assert tracker.estimate("C-RS1").pose.distance_to(machine) < 0.05
    assert tracker.add(det, EXT, moved) == "C-RS1"           # third in a row: restart there
    assert tracker.estimate("C-RS1").pose.y == pytest.approx(3.4, abs=0.05)
