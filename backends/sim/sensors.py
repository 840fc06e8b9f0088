"""The robot's sensors in the world: a planar laser (``rayTestBatch``) and a
camera (TinyRenderer, rendered only when asked).

Laser: ``laser_beams`` rays spread evenly over ``laser_fov`` (first at
``-fov/2``, last at ``+fov/2``), cast horizontally from ``ROBOT.laser_mount``
(0.22 m above the floor, so they never touch it), hitting walls, stations and
other robots (the robot's own body is masked out); Gaussian noise of
``laser_noise`` on every hit, ``inf`` where nothing is hit.

Camera: pinhole with ``CameraIntrinsics.from_fov(width, height, hfov)``,
optical frame at ``ROBOT.camera_mount`` pitched by ``camera_pitch``
(:func:`camera_model`, :func:`camera_pose`); the views themselves are
rendered by :mod:`backends.sim.camera`.
"""
from __future__ import annotations

import math

import numpy as np

from rll_bt.backend import CameraExtrinsics, CameraIntrinsics, LaserScan, Pose2D

from .bullet import pybullet
from .robot import SimRobot

ALL_GROUPS = 0x7FFFFFFF


def ray_mask(robot: SimRobot | None) -> int:
    """Ray filter mask seeing everything but ``robot``'s own body."""
    return ALL_GROUPS if robot is None else ALL_GROUPS & ~robot.ray_group


def laser_ranges(cid: int, robot: SimRobot, angles: np.ndarray, noisy: bool = True, *,
                 first: float | None = None, step: float = 0.0, robots: frozenset = frozenset()) -> np.ndarray:
    """Ranges (m) along ``angles`` (rad, laser frame) from the robot's laser
    mount; ``inf`` where nothing is hit within range; the robot's laser noise
    when ``noisy``.  A regular scan may pass its ``first`` angle and ``step``
    too: the world angles are then ``(theta + first) + step * i``, summed in
    the order lockstep games have always used (a different rounding of the
    beam angles makes a seeded game play differently).  Each body of
    ``robots`` (other robots' body ids) the rays hit is counted once in
    ``robot.laser_hits``."""
    p = pybullet()
    cfg, g = robot.config, robot.config.geometry
    angles = np.asarray(angles, dtype=float)
    n = len(angles)
    rmin, rmax = cfg.laser_range
    mx, my, mz = g.laser_mount
    pose = robot.pose
    c, s = math.cos(pose.theta), math.sin(pose.theta)
    ox, oy = pose.x + c * mx - s * my, pose.y + s * mx + c * my
    a = pose.theta + angles if first is None else pose.theta + first + step * np.arange(n)
    start = np.empty((n, 3))
    start[:, 0], start[:, 1], start[:, 2] = ox, oy, mz
    end = start.copy()
    end[:, 0] += rmax * np.cos(a)
    end[:, 1] += rmax * np.sin(a)
    hits = p.rayTestBatch(start, end, numThreads=1, collisionFilterMask=ray_mask(robot),
                          physicsClientId=cid)
    ranges = np.array([hit[2] for hit in hits]) * rmax
    bodies = np.array([hit[0] for hit in hits])
    ranges[bodies < 0] = np.inf
    if robots:
        for body in robots.intersection(bodies.tolist()):
            robot.laser_hits[body] = robot.laser_hits.get(body, 0) + 1
    if noisy and cfg.laser_noise > 0.0:
        ranges = ranges + robot.rng.normal(0.0, cfg.laser_noise, n)
    return np.where(np.isfinite(ranges), np.clip(ranges, rmin, rmax), np.inf)


def laser_scan(cid: int, robot: SimRobot, stamp: float, robots: frozenset = frozenset()) -> LaserScan:
    cfg, g = robot.config, robot.config.geometry
    n = cfg.laser_beams
    angle_min = -cfg.laser_fov / 2.0
    inc = cfg.laser_fov / (n - 1) if n > 1 else 0.0
    rmin, rmax = cfg.laser_range
    mx, my, _ = g.laser_mount
    ranges = laser_ranges(cid, robot, angle_min + inc * np.arange(n), first=angle_min, step=inc, robots=robots)
    return LaserScan(stamp, angle_min, inc, rmin, rmax, ranges, mount=Pose2D(mx, my, 0.0))


def camera_model(robot: SimRobot) -> tuple[CameraIntrinsics, CameraExtrinsics]:
    cfg = robot.config
    intr = CameraIntrinsics.from_fov(cfg.camera_width, cfg.camera_height, cfg.camera_hfov)
    extr = CameraExtrinsics(position=tuple(cfg.geometry.camera_mount), yaw=0.0, pitch=cfg.camera_pitch)
    return intr, extr


def camera_pose(robot: SimRobot, extr: CameraExtrinsics) -> tuple[np.ndarray, np.ndarray]:
    """(eye, R): camera position in the field frame and the rotation taking
    optical-frame vectors into the field frame."""
    pose = robot.pose
    c, s = math.cos(pose.theta), math.sin(pose.theta)
    yaw = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
    eye = np.array([pose.x, pose.y, 0.0]) + yaw @ np.asarray(extr.position, float)
    return eye, yaw @ extr.rotation()


def project(points: np.ndarray, eye: np.ndarray, rot: np.ndarray,
            intr: CameraIntrinsics) -> tuple[np.ndarray, np.ndarray]:
    """Pixel coordinates (N, 2) and optical depths (N,) of field-frame points."""
    cam = (np.atleast_2d(points) - eye) @ rot          # rows: optical-frame coordinates
    z = cam[:, 2]
    with np.errstate(divide="ignore", invalid="ignore"):
        u = intr.fx * cam[:, 0] / z + intr.cx
        v = intr.fy * cam[:, 1] / z + intr.cy
    return np.column_stack([u, v]), z
