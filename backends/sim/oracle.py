"""Oracle perception (gazebo-rcll style): the tags and signal towers of the
stations really in view of a robot's camera, without rendering.

A tag is seen when its centre is within ``camera_range``, all four corners
project inside the image, the marker faces the camera (angle between its
normal and the ray to the camera below ``tag_max_angle``) and a ray from the
camera to it hits nothing first.  A tower is seen when its middle light is in
range, inside the image and unoccluded.  Each detection is then dropped with
probability ``dropout``.  Tag poses get Gaussian noise: position sigma
``tag_noise_pos`` per metre of range, rotation sigma ``tag_noise_rot``.

A light detection reports the lights lit at that instant (a blinking light is
on or off depending on its phase, as a camera would see it) and ``tag_id``
is the tag of the station face turned towards the camera (None when the
camera looks at the station's side).
"""
from __future__ import annotations

import math

import cv2
import numpy as np

from rll_bt.backend import Detections, LightDetection, TagDetection

from .bullet import pybullet
from .robot import SimRobot
from .sensors import camera_model, camera_pose, project, ray_mask
from .stations import Station

RAY_STOP = 0.03            # stop occlusion rays this far before the target
SIDE_VIEW_COS = math.cos(math.radians(80.0))


def _in_image(uv: np.ndarray, z: np.ndarray, w: int, h: int) -> bool:
    return bool(np.all(z > 0.05) and np.all(uv[:, 0] >= 0) and np.all(uv[:, 0] < w)
                and np.all(uv[:, 1] >= 0) and np.all(uv[:, 1] < h))


def _clear(cid: int, robot: SimRobot, eye: np.ndarray, targets: list[np.ndarray]) -> list[bool]:
    """Whether the straight line from ``eye`` to each target is free."""
    if not targets:
        return []
    ends = []
    for t in targets:
        d = t - eye
        n = float(np.linalg.norm(d))
        ends.append((eye + d * max(0.0, (n - RAY_STOP) / n)).tolist())
    hits = pybullet().rayTestBatch([eye.tolist()] * len(ends), ends, numThreads=1,
                                   collisionFilterMask=ray_mask(robot), physicsClientId=cid)
    return [h[0] < 0 for h in hits]


def _noisy_pose(rng: np.random.Generator, rot_cam: np.ndarray, t_cam: np.ndarray,
                pos_sigma: float, rot_sigma: float) -> tuple[tuple, tuple]:
    rvec, _ = cv2.Rodrigues(rot_cam)
    tvec = t_cam.copy()
    if pos_sigma > 0:
        tvec = tvec + rng.normal(0.0, pos_sigma, 3)
    if rot_sigma > 0:
        jitter, _ = cv2.Rodrigues(rng.normal(0.0, rot_sigma, 3).reshape(3, 1))
        rvec, _ = cv2.Rodrigues(jitter @ rot_cam)
    return tuple(float(v) for v in tvec), tuple(float(v) for v in np.ravel(rvec))


def detect(cid: int, robot: SimRobot, stations: list[Station], now: float, blink_hz: float,
           tag_size: float, camera: str = "front") -> Detections:
    cfg = robot.config
    intr, extr = camera_model(robot)
    eye, rot = camera_pose(robot, extr)
    w, h, rng = intr.width, intr.height, robot.rng
    half = tag_size / 2.0
    tag_cands, light_cands = [], []
    for st in stations:
        tower = np.array(st.tower_point(1))
        if np.linalg.norm(tower - eye) > cfg.camera_range + 1.0:
            continue
        best_side, best_cos = None, SIDE_VIEW_COS
        for side in ("input", "output"):
            centre, frame = st.tag_frame(side)
            to_cam = eye - centre
            dist = float(np.linalg.norm(to_cam))
            facing = float(frame[:, 2] @ to_cam) / dist
            if facing > best_cos:
                best_side, best_cos = side, facing
            if dist > cfg.camera_range or facing < math.cos(cfg.tag_max_angle):
                continue
            x, y = frame[:, 0] * half, frame[:, 1] * half
            corners = np.array([centre - x + y, centre + x + y, centre + x - y, centre - x - y])
            uv, z = project(corners, eye, rot, intr)
            if _in_image(uv, z, w, h):
                tag_cands.append((st, side, centre, frame, uv))
        top = np.array(st.tower_point(2)) + [0, 0, st.profile.mps.tower_segment / 2]
        bottom = np.array(st.tower_point(0)) - [0, 0, st.profile.mps.tower_segment / 2]
        if np.linalg.norm(tower - eye) <= cfg.camera_range:
            uv, z = project(np.array([top, bottom, tower]), eye, rot, intr)
            if _in_image(uv[2:], z, w, h):
                light_cands.append((st, best_side, tower, uv))
    free = _clear(cid, robot, eye, [c[2] for c in tag_cands] + [c[2] for c in light_cands])
    tags, lights = [], []
    for (st, side, centre, frame, uv), ok in zip(tag_cands, free[:len(tag_cands)]):
        if not ok or (cfg.dropout > 0 and rng.random() < cfg.dropout):
            continue
        t_cam = (centre - eye) @ rot
        tvec, rvec = _noisy_pose(rng, rot.T @ frame, t_cam,
                                 cfg.tag_noise_pos * float(np.linalg.norm(t_cam)), cfg.tag_noise_rot)
        tags.append(TagDetection(st.tag_id(side), tvec, rvec,
                                 tuple((float(u), float(v)) for u, v in uv), camera))
    for (st, side, _, uv), ok in zip(light_cands, free[len(tag_cands):]):
        if not ok or (cfg.dropout > 0 and rng.random() < cfg.dropout):
            continue
        r = st.profile.mps.tower_radius
        depth = float(((np.array(st.tower_point(1)) - eye) @ rot)[2])
        half_w = max(1, int(round(intr.fx * r / depth)))
        u = int(round(uv[2, 0]))
        v0, v1 = sorted((int(round(uv[0, 1])), int(round(uv[1, 1]))))
        box = (u - half_w, v0, 2 * half_w, max(1, v1 - v0))
        lights.append(LightDetection(box, st.light_code(now, blink_hz), 1.0, camera=camera,
                                     tag_id=st.tag_id(side) if side else None))
    return Detections(now, tuple(tags), tuple(lights), extr)
