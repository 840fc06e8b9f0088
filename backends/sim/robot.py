"""A simulated Robotino: kinematic omnidirectional base, odometry, bumper,
battery and gripper state.  Sensors are in :mod:`.sensors`, the world
decides collisions.

Motion: the commanded body velocity (robot frame: x forward, y left, rad/s
counter-clockwise) is clipped to the speed limits of ``rules.ROBOT``
(0.7 m/s, ``max_omega``) and, with ``wheel_rpm_max`` set (3000 on a
Robotino 3; off by default for now), to what the wheels can do (a command
beyond it is scaled down whole, as the robotino backend's host scales it:
~0.68 m/s straight ahead, less while turning), approached with its
acceleration limits (``max_accel`` when speeding up, ``max_decel`` when
slowing down, ``max_alpha``) and integrated each time step.  A drive
command older than ``RobotConfig.deadman`` seconds of sim time is dropped (the robot brakes).
A robot whose wheels an emulated base firmware turns (``follows_wheels``,
:mod:`.hardware_parts`) moves at the wheels' speeds as they are: the host
ramped its commands and the firmware its motors, and the host's odometry
counts exactly those speeds.

Odometry integrates the motion the wheels made, with a random-walk error:
per step the travelled distance gets Gaussian noise of
``odom_noise_trans * sqrt(distance)`` and the heading
``odom_noise_rot * sqrt(|turn| + distance)`` plus a systematic
``odom_drift`` radians per metre.  A blocked robot's wheels stall (odometry
stands still), unless ``odom_slip`` is set: then they keep turning at the
commanded, acceleration-limited speed and the odometry runs away from the
truth.  Its frame starts at (0, 0, 0) at the start pose
(``odom_frame="zero"``, like a real Robotino) or equals the field frame at
the start (``odom_frame="field"``).
"""
from __future__ import annotations

import functools
import math
from dataclasses import dataclass, field, replace

import numpy as np

from backends.robotino.kinematics import OmniKinematics
from rll_bt.backend import Battery, Pose2D, wrap_angle
from rll_bt.rules import MPS, ROBOT, WORKPIECE, RobotGeometry

from .gripper import Gripper

#: gripper height at rest: the middle of a base standing on a conveyor
GRIPPER_HOME_Z = round(MPS.belt_height + WORKPIECE.base_height / 2.0, 4)


@functools.lru_cache(maxsize=8)
def _drive(rpm_max: float) -> OmniKinematics:
    """The Robotino 3 omni drive with motor limit ``rpm_max``."""
    return OmniKinematics(rpm_max=rpm_max)


@dataclass(frozen=True)
class RobotConfig:
    """Per-robot simulation settings (all SI units).  Any field can be
    overridden through ``open_backend("sim", ..., <field>=value)``."""
    # base
    deadman: float = 0.5                  # s of sim time a drive command stays valid
    #: motor speed limit of the omni drive (Robotino 3: 3000 rpm, rb 0.175 m, rw 0.06 m, gear 32; a command
    #: beyond it is scaled down whole, as the robotino host does): ~0.68 m/s ahead, less turning.  None (the
    #: default for now): no limit; 3000.0 is the real robot (the tables were measured without it: benchmarks/README.md)
    wheel_rpm_max: float | None = None
    # odometry
    odom_frame: str = "zero"              # "zero" or "field"
    odom_noise_trans: float = 0.01        # m per sqrt(m)
    odom_noise_rot: float = 0.01          # rad per sqrt(rad or m)
    odom_drift: float = 0.0               # rad per metre, systematic
    odom_slip: bool = False               # blocked: wheels keep turning, odometry integrates the command
    # laser (mount from rules.ROBOT.laser_mount)
    laser_beams: int = ROBOT.laser_beams
    laser_fov: float = ROBOT.laser_fov
    laser_range: tuple[float, float] = ROBOT.laser_range
    laser_noise: float = 0.01             # m, Gaussian sigma
    laser_rate: float = 10.0              # Hz; faster calls return the latest scan
    # camera (mount from rules.ROBOT.camera_mount)
    camera_width: int = 320
    camera_height: int = 240
    camera_hfov: float = ROBOT.camera_hfov
    camera_pitch: float = 0.0             # rad, positive looks down
    camera_rate: float | None = None      # Hz; faster calls return the latest frame (None: no limit)
    # oracle perception
    camera_range: float = ROBOT.camera_range
    tag_max_angle: float = math.radians(70.0)   # tag normal to viewing ray
    tag_noise_pos: float = 0.01           # m of position sigma per m of range
    tag_noise_rot: float = 0.02           # rad
    dropout: float = 0.0                  # probability a visible tag or light is missed
    # gripper
    grab_failure: float = 0.0             # probability a close over a workpiece misses it
    grab_tolerance: float = 0.03          # m, horizontal, gripper point to workpiece centre
    grab_tolerance_z: float = 0.03        # m, gripper height to the workpiece's mid-base height
    place_tolerance: float = 0.04         # m, horizontal, gripper point to a slot centre
    place_tolerance_z: float = 0.05
    gripper_speed: float = 0.1            # m/s per axis
    gripper_time: float = 0.5             # s to open or close
    # battery
    battery_life: float = 7200.0          # s from full to empty when idle
    geometry: RobotGeometry = ROBOT

    def with_options(self, **options) -> RobotConfig:
        unknown = sorted(set(options) - set(self.__dataclass_fields__))
        if unknown:
            raise TypeError(f"unknown sim robot option(s): {', '.join(unknown)} "
                            f"(known: {', '.join(sorted(self.__dataclass_fields__))})")
        cfg = replace(self, **options)
        if cfg.odom_frame not in ("zero", "field"):
            raise ValueError(f"odom_frame must be 'zero' or 'field', not {cfg.odom_frame!r}")
        return cfg


def _approach(current: float, target: float, up: float, down: float) -> float:
    limit = up if abs(target) > abs(current) and current * target >= 0 else down
    return current + max(-limit, min(limit, target - current))


@dataclass
class Collision:
    """One collision event: a robot's motion blocked after a free one."""
    time: float
    robot: tuple[str, int]
    obstacle: str                         # machine name, "wall", or "robot TEAM/N"
    pose: Pose2D | None = None            # the robot's true pose at the contact (field frame)
    speed: float = 0.0                    # m/s the robot was moving at when it hit


@dataclass
class SimRobot:
    """State of one robot in the world; see the module docstring."""
    team: str
    number: int
    start: Pose2D
    config: RobotConfig
    rng: np.random.Generator
    body: int = -1
    ray_group: int = 0
    pose: Pose2D = field(init=False)
    velocity: tuple[float, float, float] = (0.0, 0.0, 0.0)      # executed, robot frame
    #: the command is the wheels' actual speed (an emulated firmware ramps them): executed as it is, without
    #: the world's speed and acceleration limits (ramping it once more, the world turned up to 0.8 rad on
    #: after a turn at 1.6 rad/s was stopped, while the host's odometry had the wheels standing)
    follows_wheels: bool = False
    command: tuple[float, float, float] = (0.0, 0.0, 0.0)
    command_stamp: float = -math.inf
    odom: Pose2D = field(init=False)
    collisions: int = 0                   # collision events (a motion blocked by something not yet touched)
    touching: set = field(default_factory=set)   # what the robot is in contact with (names as in Collision)
    blocked_steps: int = 0
    blocked: bool = False                 # the last step's motion was blocked
    contact: bool = False                 # touching something after the last step
    distance: float = 0.0                 # metres travelled
    born: float = 0.0                     # sim time the robot was added
    holding: int | None = None            # id of the workpiece in the gripper
    last_scan: object = None
    #: bodies of other robots its laser scans have hit: body id -> scans (see World.laser_sightings)
    laser_hits: dict = field(default_factory=dict)
    last_image: object = None
    camera_frame: tuple | None = None     # (what it showed, image) of the last sparse frame
    gripper: Gripper = field(init=False)

    def __post_init__(self):
        self.pose = self.start
        self.odom = Pose2D() if self.config.odom_frame == "zero" else self.start
        self.gripper = Gripper((0.0, 0.0, GRIPPER_HOME_Z), self.config.gripper_speed,
                               self.config.gripper_time)
        self.radius = self.config.geometry.radius

    @property
    def key(self) -> tuple[str, int]:
        return (self.team, self.number)

    @property
    def name(self) -> str:
        return f"{self.team}/{self.number}"

    # -- motion -------------------------------------------------------------
    def drive(self, vx: float, vy: float, omega: float, now: float) -> None:
        for v in (vx, vy, omega):
            if not math.isfinite(v):
                raise ValueError(f"drive command must be finite, got ({vx}, {vy}, {omega})")
        self.command = (float(vx), float(vy), float(omega))
        self.command_stamp = now

    def stop(self, now: float) -> None:
        self.command = (0.0, 0.0, 0.0)
        self.command_stamp = now

    def target_velocity(self, now: float) -> tuple[float, float, float]:
        g = self.config.geometry
        if now - self.command_stamp > self.config.deadman:
            return (0.0, 0.0, 0.0)
        vx, vy, w = self.command
        speed = math.hypot(vx, vy)
        if speed > g.max_speed:
            vx, vy = vx * g.max_speed / speed, vy * g.max_speed / speed
        w = max(-g.max_omega, min(g.max_omega, w))
        if self.config.wheel_rpm_max:
            vx, vy, w = _drive(self.config.wheel_rpm_max).clamped(vx, vy, w)
        return vx, vy, w

    def propose(self, dt: float, now: float) -> tuple[Pose2D, tuple[float, float, float]]:
        """Next pose and velocity if nothing blocks the motion."""
        g = self.config.geometry
        if self.follows_wheels:
            vx, vy, w = self.command if now - self.command_stamp <= self.config.deadman else (0.0, 0.0, 0.0)
            if vx == 0.0 and vy == 0.0 and w == 0.0:
                return self.pose, (0.0, 0.0, 0.0)
            return self._integrate(vx, vy, w, dt), (vx, vy, w)
        tx, ty, tw = self.target_velocity(now)
        vx, vy, w = self.velocity
        # accelerate the velocity vector as a whole (limits apply to its length)
        dvx, dvy = tx - vx, ty - vy
        dv = math.hypot(dvx, dvy)
        limit = (g.max_accel if math.hypot(tx, ty) > math.hypot(vx, vy) else g.max_decel) * dt
        if dv > limit:
            dvx, dvy = dvx * limit / dv, dvy * limit / dv
        vx, vy = vx + dvx, vy + dvy
        w = _approach(w, tw, g.max_alpha * dt, g.max_alpha * dt)
        if abs(vx) < 1e-9 and abs(vy) < 1e-9 and abs(w) < 1e-9:
            return self.pose, (0.0, 0.0, 0.0)
        return self._integrate(vx, vy, w, dt), (vx, vy, w)

    def _integrate(self, vx: float, vy: float, w: float, dt: float) -> Pose2D:
        th = self.pose.theta + w * dt / 2.0
        c, s = math.cos(th), math.sin(th)
        return Pose2D(self.pose.x + (c * vx - s * vy) * dt, self.pose.y + (s * vx + c * vy) * dt,
                      wrap_angle(self.pose.theta + w * dt))

    def commit(self, pose: Pose2D, velocity, dt: float, wheels: Pose2D | None = None) -> None:
        """Take the step the world allowed and integrate the odometry from
        the wheels' motion (``wheels``, default: the motion made)."""
        old = self.pose
        self.pose, self.velocity = pose, velocity
        self.distance += math.hypot(pose.x - old.x, pose.y - old.y)
        if wheels is None:
            if pose is old:
                return
            wheels = pose.relative_to(old)
        self._integrate_odometry(wheels)

    def _integrate_odometry(self, delta: Pose2D) -> None:
        dist = math.hypot(delta.x, delta.y)
        cfg = self.config
        dx, dy, dth = delta.x, delta.y, delta.theta
        if cfg.odom_noise_trans > 0.0 or cfg.odom_noise_rot > 0.0:
            n = self.rng.standard_normal(3).tolist()
            st = cfg.odom_noise_trans * math.sqrt(dist)
            dx += n[0] * st
            dy += n[1] * st
            dth += n[2] * cfg.odom_noise_rot * math.sqrt(abs(delta.theta) + dist)
        dth += cfg.odom_drift * dist
        self.odom = self.odom.compose(Pose2D(dx, dy, dth))

    # -- battery ------------------------------------------------------------
    def battery(self, now: float) -> Battery:
        """A slowly draining lead battery: idle drain over ``battery_life``
        seconds, plus driving costs (200 m of driving = 20 % of a charge)."""
        soc = max(0.0, 1.0 - (now - self.born) / self.config.battery_life - self.distance / 1000.0)
        speed = math.hypot(self.velocity[0], self.velocity[1])
        return Battery(voltage=22.0 + 3.5 * soc, current=0.8 + 3.0 * speed, soc=soc)
