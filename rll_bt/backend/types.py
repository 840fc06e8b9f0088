"""Data types that cross the backend interface.

Frames: the robot frame has x forward, y left, z up; angles in radians,
counter-clockwise positive.  Poses in the field frame follow the rules
profile (x along the long side, y across, origin at the centre of the
insertion-side wall).
"""
from __future__ import annotations

import enum
import math
from dataclasses import dataclass, field

import numpy as np


def wrap_angle(a: float) -> float:
    """Wrap an angle to [-pi, pi)."""
    return (a + math.pi) % (2.0 * math.pi) - math.pi


@dataclass(frozen=True)
class Pose2D:
    x: float = 0.0
    y: float = 0.0
    theta: float = 0.0

    def compose(self, other: Pose2D) -> Pose2D:
        """``self`` then ``other`` expressed in ``self``'s frame."""
        c, s = math.cos(self.theta), math.sin(self.theta)
        return Pose2D(self.x + c * other.x - s * other.y,
                      self.y + s * other.x + c * other.y,
                      wrap_angle(self.theta + other.theta))

    def inverse(self) -> Pose2D:
        c, s = math.cos(self.theta), math.sin(self.theta)
        return Pose2D(-c * self.x - s * self.y, s * self.x - c * self.y, wrap_angle(-self.theta))

    def relative_to(self, frame: Pose2D) -> Pose2D:
        """This pose expressed in ``frame``."""
        return frame.inverse().compose(self)

    def distance_to(self, other: Pose2D) -> float:
        return math.hypot(self.x - other.x, self.y - other.y)


@dataclass(frozen=True)
class Odometry:
    """Dead-reckoned pose in the odometry frame and velocities in the robot frame."""
    stamp: float
    pose: Pose2D
    vx: float = 0.0
    vy: float = 0.0
    omega: float = 0.0


@dataclass(frozen=True)
class LaserScan:
    """A planar scan.  ``ranges[i]`` is at ``angle_min + i * angle_increment``
    in the laser frame; readings beyond ``range_max`` are ``inf``."""
    stamp: float
    angle_min: float
    angle_increment: float
    range_min: float
    range_max: float
    ranges: np.ndarray
    mount: Pose2D = Pose2D()          # laser frame in the robot frame

    @property
    def angles(self) -> np.ndarray:
        return self.angle_min + self.angle_increment * np.arange(len(self.ranges))


@dataclass(frozen=True)
class CameraIntrinsics:
    width: int
    height: int
    fx: float
    fy: float
    cx: float
    cy: float
    distortion: tuple[float, ...] = (0.0, 0.0, 0.0, 0.0, 0.0)

    @property
    def matrix(self) -> np.ndarray:
        return np.array([[self.fx, 0.0, self.cx], [0.0, self.fy, self.cy], [0.0, 0.0, 1.0]])

    @classmethod
    def from_fov(cls, width: int, height: int, hfov_rad: float) -> CameraIntrinsics:
        f = (width / 2.0) / math.tan(hfov_rad / 2.0)
        return cls(width, height, f, f, width / 2.0, height / 2.0)


@dataclass(frozen=True)
class CameraExtrinsics:
    """Camera optical frame (z forward, x right, y down) in the robot frame.

    ``position`` is (x, y, z) metres; ``yaw``/``pitch`` rotate the camera's
    viewing direction about the robot's z and the camera's horizontal axis
    (pitch positive looks down).
    """
    position: tuple[float, float, float] = (0.2, 0.0, 0.6)
    yaw: float = 0.0
    pitch: float = 0.0

    def rotation(self) -> np.ndarray:
        """3x3 rotation taking optical-frame vectors into the robot frame."""
        # optical axes expressed in a level, forward-looking robot frame
        base = np.array([[0.0, 0.0, 1.0], [-1.0, 0.0, 0.0], [0.0, -1.0, 0.0]])
        cp, sp = math.cos(self.pitch), math.sin(self.pitch)
        pitch = np.array([[cp, 0.0, sp], [0.0, 1.0, 0.0], [-sp, 0.0, cp]])  # about robot y
        cy, sy = math.cos(self.yaw), math.sin(self.yaw)
        yaw = np.array([[cy, -sy, 0.0], [sy, cy, 0.0], [0.0, 0.0, 1.0]])
        return yaw @ pitch @ base


@dataclass(frozen=True)
class CameraImage:
    stamp: float
    image: np.ndarray                 # H x W x 3, uint8, BGR (OpenCV order)
    intrinsics: CameraIntrinsics
    extrinsics: CameraExtrinsics
    camera: str = "front"


class GripperState(enum.Enum):
    IDLE = "idle"
    MOVING = "moving"
    ERROR = "error"
    UNKNOWN = "unknown"


@dataclass(frozen=True)
class GripperStatus:
    state: GripperState
    is_open: bool
    position: tuple[float, float, float] = (0.0, 0.0, 0.0)   # metres, gripper axes
    holding: bool | None = None       # None when the hardware cannot tell
    message: str = ""
    #: a workpiece between the fingers (the gripper's workpiece sensor, read with the fingers
    #: open at a place: is there anything to take?); None when the gripper has no such sensor
    sensed: bool | None = None


@dataclass(frozen=True)
class Battery:
    voltage: float
    current: float = 0.0
    soc: float | None = None          # 0..1 state of charge, None when unknown
    external_power: bool = False


@dataclass(frozen=True)
class TagDetection:
    """A fiducial seen by a camera: pose of the tag in the camera optical frame.

    ``rvec``/``tvec`` follow OpenCV's solvePnP convention (tag frame into the
    optical frame; the tag's z axis points out of the marker face)."""
    tag_id: int
    tvec: tuple[float, float, float]
    rvec: tuple[float, float, float]
    corners: tuple[tuple[float, float], ...] = ()
    camera: str = "front"


LIGHT_NAMES = ("green", "yellow", "red")   # bit 0, 1, 2 of the paper's formula (1)


def light_state_code(green: bool, yellow: bool, red: bool) -> int:
    """The paper's formula (1): green 1, yellow 2, red 4."""
    return (1 if green else 0) | (2 if yellow else 0) | (4 if red else 0)


@dataclass(frozen=True)
class LightDetection:
    """A signal tower seen in one frame.  ``state`` is 0..7 (green 1, yellow 2, red 4)."""
    box: tuple[int, int, int, int]                     # x, y, w, h in pixels
    state: int
    score: float = 1.0
    probabilities: tuple[float, ...] = ()
    camera: str = "front"
    tag_id: int | None = None          # the station the tower belongs to, when known

    @property
    def lights(self) -> dict[str, bool]:
        return {name: bool(self.state >> i & 1) for i, name in enumerate(LIGHT_NAMES)}


@dataclass(frozen=True)
class Detections:
    """What a camera frame shows, as a backend's own perception reports it."""
    stamp: float
    tags: tuple[TagDetection, ...] = ()
    lights: tuple[LightDetection, ...] = ()
    extrinsics: CameraExtrinsics = field(default_factory=CameraExtrinsics)
