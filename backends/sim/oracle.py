"""Oracle perception (gazebo-rcll style): the tags and signal towers of the
stations really in view of a robot's camera, without rendering.

A tag is seen when its centre is within ``camera_range``, all four corners
project inside the image, the marker faces the camera (angle between its
normal and the ray to the camera below ``tag_max_angle``) and rays from the
camera to its centre and to its four corners (a little inside the edge) hit
nothing first: a marker half hidden cannot be decoded.  A tower is seen when
its middle light is in range and inside the image, and the rays to the
middle light and to at least one of its ends (bottom light, top of the
housing) are free.  Each detection is then dropped with
probability ``dropout``.  Tag poses get Gaussian noise: position sigma
``tag_noise_pos`` per metre of range, rotation sigma ``tag_noise_rot``.

A light detection reports the lights lit at that instant (a blinking light is
on or off depending on its phase, as a camera would see it) and ``tag_id``
is the tag of the station face turned towards the camera (None when the
camera looks at the station's side).

The stations never move, so :class:`OracleScene` keeps their tag corners and
tower points in arrays and tests every station at once.
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
CORNER_INSET = 0.85        # corner rays aim at this fraction of the way from the tag centre
SIDE_VIEW_COS = math.cos(math.radians(80.0))
SIDES = ("input", "output")


def _noisy_pose(rng: np.random.Generator, rot_cam: np.ndarray, t_cam: np.ndarray,
                pos_sigma: float, rot_sigma: float) -> tuple[tuple, tuple]:
    tvec = t_cam + rng.normal(0.0, pos_sigma, 3) if pos_sigma > 0 else t_cam
    if rot_sigma > 0:
        jitter, _ = cv2.Rodrigues(rng.normal(0.0, rot_sigma, 3).reshape(3, 1))
        rot_cam = jitter @ rot_cam
    rvec, _ = cv2.Rodrigues(rot_cam)
    return tuple(float(v) for v in tvec), tuple(float(v) for v in np.ravel(rvec))


class OracleScene:
    """Tag and tower geometry of all stations, ready for :meth:`detect`."""

    def __init__(self, stations: list[Station], tag_size: float):
        self.stations = stations
        half = tag_size / 2.0
        centres, frames, corners, ids = [], [], [], []
        for st in stations:
            for side in SIDES:
                c, f = st.tag_frame(side)
                x, y = f[:, 0] * half, f[:, 1] * half
                centres.append(c)
                frames.append(f)
                corners.append([c - x + y, c + x + y, c + x - y, c - x - y])
                ids.append(st.tag_id(side))
        n = len(stations)
        self.tag_centre = np.array(centres).reshape(2 * n, 3)
        self.tag_frame = np.array(frames).reshape(2 * n, 3, 3)
        self.tag_normal = self.tag_frame[:, :, 2] if n else np.zeros((0, 3))
        self.tag_corners = np.array(corners).reshape(2 * n, 4, 3)
        self.tag_ids = ids
        seg = stations[0].profile.mps.tower_segment if stations else 0.0
        self.tower_mid = np.array([st.tower_point(1) for st in stations]).reshape(n, 3)
        self.tower_top = np.array([st.tower_point(2) for st in stations]).reshape(n, 3) + [0, 0, seg / 2]
        self.tower_bottom = np.array([st.tower_point(0) for st in stations]).reshape(n, 3) - [0, 0, seg / 2]
        self.tower_radius = stations[0].profile.mps.tower_radius if stations else 0.0

    def _tag_targets(self, i: int) -> list[np.ndarray]:
        c = self.tag_centre[i]
        return [c] + [c + CORNER_INSET * (k - c) for k in self.tag_corners[i]]

    def detect(self, cid: int, robot: SimRobot, now: float, blink_hz: float,
               camera: str = "front") -> Detections:
        cfg, rng = robot.config, robot.rng
        intr, extr = camera_model(robot)
        if not self.stations:
            return Detections(now, (), (), extr)
        eye, rot = camera_pose(robot, extr)
        w, h = intr.width, intr.height

        def inside(uv, z):
            return (z > 0.05) & (uv[..., 0] >= 0) & (uv[..., 0] < w) & (uv[..., 1] >= 0) & (uv[..., 1] < h)

        to_cam = eye - self.tag_centre
        dist = np.linalg.norm(to_cam, axis=1)
        facing = np.einsum("ij,ij->i", self.tag_normal, to_cam) / dist
        cand = np.flatnonzero((dist <= cfg.camera_range) & (facing >= math.cos(cfg.tag_max_angle)))
        uv, z = project(self.tag_corners[cand].reshape(-1, 3), eye, rot, intr)
        uv, z = uv.reshape(-1, 4, 2), z.reshape(-1, 4)
        seen = inside(uv, z).all(axis=1)
        tags = [(int(i), uv[k]) for k, i in enumerate(cand) if seen[k]]

        n = len(self.stations)
        tdist = np.linalg.norm(self.tower_mid - eye, axis=1)
        tuv, tz = project(np.concatenate([self.tower_mid, self.tower_top, self.tower_bottom]), eye, rot, intr)
        mid_in = inside(tuv[:n], tz[:n]) & (tdist <= cfg.camera_range)
        towers = [int(s) for s in np.flatnonzero(mid_in)]
        side_facing = facing.reshape(n, 2)

        # five rays per tag (centre, corners), three per tower (middle, bottom, top)
        targets = [p for i, _ in tags for p in self._tag_targets(i)]
        targets += [p for s in towers for p in (self.tower_mid[s], self.tower_bottom[s], self.tower_top[s])]
        free = np.asarray(_clear(cid, robot, eye, targets), bool)
        tag_free = free[:5 * len(tags)].reshape(-1, 5).all(axis=1)
        tower_rays = free[5 * len(tags):].reshape(-1, 3)
        tower_free = tower_rays[:, 0] & tower_rays[:, 1:].any(axis=1)
        out_tags, out_lights = [], []
        for (i, corners), ok in zip(tags, tag_free):
            if not ok or (cfg.dropout > 0 and rng.random() < cfg.dropout):
                continue
            t_cam = (self.tag_centre[i] - eye) @ rot
            tvec, rvec = _noisy_pose(rng, rot.T @ self.tag_frame[i], t_cam,
                                     cfg.tag_noise_pos * float(np.linalg.norm(t_cam)), cfg.tag_noise_rot)
            out_tags.append(TagDetection(self.tag_ids[i], tvec, rvec,
                                         tuple((float(u), float(v)) for u, v in corners), camera))
        for s, ok in zip(towers, tower_free):
            if not ok or (cfg.dropout > 0 and rng.random() < cfg.dropout):
                continue
            st = self.stations[s]
            best = int(np.argmax(side_facing[s]))
            tag_id = st.tag_id(SIDES[best]) if side_facing[s, best] > SIDE_VIEW_COS else None
            half_w = max(1, int(round(intr.fx * self.tower_radius / max(tz[s], 1e-3))))
            u = int(round(tuv[s, 0]))
            v0, v1 = sorted((int(round(tuv[n + s, 1])), int(round(tuv[2 * n + s, 1]))))
            out_lights.append(LightDetection((u - half_w, v0, 2 * half_w, max(1, v1 - v0)),
                                             st.light_code(now, blink_hz), 1.0, camera=camera, tag_id=tag_id))
        return Detections(now, tuple(out_tags), tuple(out_lights), extr)


def _clear(cid: int, robot: SimRobot, eye: np.ndarray, targets: list[np.ndarray]) -> list[bool]:
    """Whether the straight line from ``eye`` to each target is free."""
    if not targets:
        return []
    t = np.array(targets)
    d = t - eye
    n = np.linalg.norm(d, axis=1, keepdims=True)
    ends = eye + d * np.maximum(0.0, (n - RAY_STOP) / n)
    starts = np.repeat(eye[None, :], len(t), axis=0)
    hits = pybullet().rayTestBatch(starts, ends, numThreads=1, collisionFilterMask=ray_mask(robot),
                                   physicsClientId=cid)
    return [hit[0] < 0 for hit in hits]
