"""A 2D kinematic world of walls, stations and round robots.

Everything is in the field frame (metres, radians).  Each robot follows its
commanded body velocity through acceleration limits; odometry integrates
the true motion with multiplicative noise; the laser casts rays exactly
against walls, station footprints and other robots, plus Gaussian range
noise; a move that would overlap a wall, station or robot is refused and
counted as a collision (once per contact).  Tags are reported like a simulation oracle: the
station tags in the camera's field of view and range, facing the camera,
with OpenCV's rvec/tvec in the camera optical frame.

The gripper follows the simulation's conventions: axes x (0..0.15 m,
forward beyond ``RobotGeometry.gripper_reach``), y (-0.1..0.1 m, left) and
z (0..1 m, height above the floor), commands queued and run one after the
other (moves at ``gripper_speed`` per axis, fingers in ``finger_time``).
Closing picks up a workpiece whose centre is within ``grab_tolerance``
horizontally and vertically of the gripper point (unless
``fail_next_grab``); opening puts it down where the gripper is.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import cv2
import numpy as np

from rll_bt.backend import (
    Backend,
    BackendError,
    CameraExtrinsics,
    Capability,
    Detections,
    GripperState,
    GripperStatus,
    LaserScan,
    Odometry,
    Pose2D,
    TagDetection,
    wrap_angle,
)
from rll_bt.clock import SimClock
from rll_bt.rules import MPS, ROBOT, MpsGeometry, Profile, RobotGeometry

from ..maps import FieldMap, cast_rays, station_footprint
from ..maps.field_map import polygon_edges


@dataclass
class Station:
    name: str
    pose: Pose2D
    input_tag: int
    output_tag: int

    def tag_pose(self, side: str, mps: MpsGeometry = MPS) -> Pose2D:
        """Tag centre with the yaw its face points to (field frame)."""
        if side == "INPUT":
            return self.pose.compose(Pose2D(mps.depth / 2.0, mps.belt_offset_y, 0.0))
        return self.pose.compose(Pose2D(-mps.depth / 2.0, mps.belt_offset_y, math.pi))


@dataclass
class Workpiece:
    """A base; ``z`` is the height of its bottom (0 on the floor)."""
    x: float
    y: float
    z: float = 0.0
    held_by: int | None = None


class _Gripper:
    """Queued gripper actions: ("move", (x, y, z)), ("open",), ("close",)."""

    def __init__(self, home: tuple[float, float, float], speed: float = 0.1, finger_time: float = 0.5):
        self.pos = np.array(home, dtype=float)
        self.is_open = True
        self.speed = speed
        self.finger_time = finger_time
        self.queue: list[tuple] = []
        self.current: tuple | None = None
        self.until = 0.0
        self.holding: Workpiece | None = None

    @property
    def busy(self) -> bool:
        return self.current is not None or bool(self.queue)

    def advance(self, now: float, dt: float) -> list[str]:
        """Run the queue up to ``now``; returns finger actions that finished."""
        done = []
        while True:
            if self.current is None:
                if not self.queue:
                    return done
                self.current = self.queue.pop(0)
                if self.current[0] != "move":
                    self.until = now + self.finger_time
            kind = self.current[0]
            if kind == "move":
                d = np.asarray(self.current[1]) - self.pos
                n = float(np.linalg.norm(d, ord=np.inf))
                step = self.speed * dt
                if n > step:
                    self.pos = self.pos + d * (step / n)
                    return done
                self.pos = np.asarray(self.current[1], dtype=float)
            else:
                if now < self.until:
                    return done
                self.is_open = kind == "open"
                done.append(kind)
            self.current = None


class FlatWorld:
    """Walls from ``field_map`` (its boundary and extra walls; its obstacles
    are *not* used: stations are added with :meth:`add_station`)."""

    def __init__(self, field_map: FieldMap, clock: SimClock | None = None, seed: int = 0,
                 odom_noise: tuple[float, float] = (0.02, 0.02), range_noise: float = 0.01,
                 geometry: RobotGeometry = ROBOT, mps: MpsGeometry = MPS):
        self.map = field_map
        self.clock = clock or SimClock()
        self.rng = np.random.default_rng(seed)
        self.odom_noise = odom_noise
        self.range_noise = range_noise
        self.geometry = geometry
        self.mps = mps
        self.stations: dict[str, Station] = {}
        self.workpieces: list[Workpiece] = []
        self.robots: list[FlatRobot] = []
        self.collisions = 0
        self.fail_next_grab = False
        self.grab_tolerance = 0.03
        self.gripper_home_z = mps.belt_height + 0.0225 / 2.0
        self._walls = np.array(field_map.segments()[:len(field_map.boundary)])
        self._segments = self._walls

    @classmethod
    def from_profile(cls, profile: Profile, **kw) -> FlatWorld:
        return cls(FieldMap.from_profile(profile), geometry=profile.robot, mps=profile.mps, **kw)

    # -- building ---------------------------------------------------------
    def add_station(self, name: str, pose: Pose2D, tags: tuple[int, int]) -> Station:
        st = Station(name, pose, tags[0], tags[1])
        self.stations[name] = st
        edges = [polygon_edges(station_footprint(s.pose, self.mps)) for s in self.stations.values()]
        self._segments = np.concatenate([self._walls] + edges, axis=0)
        return st

    def add_robot(self, pose: Pose2D) -> FlatRobot:
        robot = FlatRobot(self, len(self.robots), pose)
        self.robots.append(robot)
        return robot

    def add_workpiece(self, x: float, y: float, z: float = 0.0) -> Workpiece:
        wp = Workpiece(x, y, z)
        self.workpieces.append(wp)
        return wp

    def slot_point(self, station: str, side: str, lateral: float | None = None,
                   inset: float = 0.03) -> tuple[float, float, float]:
        """Field point of a place on a station face: ``lateral`` machine-frame
        y (default the belt), ``inset`` inside the face, at belt height."""
        st = self.stations[station]
        sx = 1.0 if side == "INPUT" else -1.0
        y = self.mps.belt_offset_y if lateral is None else lateral
        p = st.pose.compose(Pose2D(sx * (self.mps.depth / 2.0 - inset), y, 0.0))
        return p.x, p.y, self.mps.belt_height

    def workpiece_at(self, station: str, side: str, lateral: float | None = None) -> Workpiece:
        """Put a workpiece on a station's slot (conveyor end, shelf, slide)."""
        return self.add_workpiece(*self.slot_point(station, side, lateral))

    # -- stepping ---------------------------------------------------------
    def step(self, dt: float = 0.05) -> None:
        """Advance the clock and move every robot by ``dt`` seconds."""
        self.clock.advance(dt)
        for robot in self.robots:
            robot._integrate(dt)

    def penetration(self, pose: Pose2D, ignore: int) -> float:
        """How deep (m) a robot at ``pose`` would overlap a wall, station or
        another robot; 0 when free (the walls keep robots in the field)."""
        r = self.geometry.radius
        seg = self._segments
        p = np.array([pose.x, pose.y])
        a, b = seg[:, :2], seg[:, 2:]
        ab = b - a
        t = np.clip(((p - a) * ab).sum(1) / np.maximum((ab * ab).sum(1), 1e-12), 0.0, 1.0)
        d = np.hypot(*(a + ab * t[:, None] - p).T)
        depth = max(r - float(d.min()), 0.0)
        for other in self.robots:
            if other.index != ignore:
                gap = math.hypot(other.true_pose.x - pose.x, other.true_pose.y - pose.y)
                depth = max(depth, 2 * r - gap)
        return depth

    def scan(self, robot: FlatRobot, angles_laser: np.ndarray, mount: Pose2D,
             range_max: float) -> np.ndarray:
        origin = robot.true_pose.compose(mount)
        ang = angles_laser + origin.theta
        r = cast_rays(np.array([origin.x, origin.y]), ang, self._segments, range_max)
        for other in self.robots:
            if other.index == robot.index:
                continue
            r = np.minimum(r, _ray_circle(origin, ang, other.true_pose, self.geometry.radius))
        noisy = r + self.rng.normal(0.0, self.range_noise, len(r))
        return np.where(np.isfinite(r) & (noisy < range_max), noisy, np.inf)


def _ray_circle(origin: Pose2D, angles: np.ndarray, centre: Pose2D, radius: float) -> np.ndarray:
    dx, dy = centre.x - origin.x, centre.y - origin.y
    c, s = np.cos(angles), np.sin(angles)
    along = c * dx + s * dy
    perp2 = dx * dx + dy * dy - along * along
    half = np.sqrt(np.maximum(radius * radius - perp2, 0.0))
    t = along - half
    return np.where((perp2 <= radius * radius) & (t > 0), t, np.inf)


class FlatRobot(Backend):
    name = "flat"

    def __init__(self, world: FlatWorld, index: int, pose: Pose2D):
        self.world = world
        self.index = index
        self.true_pose = pose
        self.odom_pose = Pose2D()
        self.cmd = np.zeros(3)
        self.vel = np.zeros(3)
        self.gripper = _Gripper((0.0, 0.0, world.gripper_home_z))
        self.laser_beams = world.geometry.laser_beams
        self.laser_fov = world.geometry.laser_fov
        self.range_max = world.geometry.laser_range[1]
        lx, ly, _ = world.geometry.laser_mount
        self.laser_mount = Pose2D(lx, ly, 0.0)
        cx, cy, cz = world.geometry.camera_mount
        self.extrinsics = CameraExtrinsics((cx, cy, cz), 0.0, 0.0)
        self.collisions = 0
        self.in_contact = False
        self.tag_noise = 0.0
        self._scan_cache: tuple[float, LaserScan] | None = None

    @property
    def capabilities(self) -> Capability:
        return (Capability.DRIVE | Capability.ODOMETRY | Capability.LASER | Capability.GRIPPER
                | Capability.DETECTIONS)

    # -- motion -----------------------------------------------------------
    def drive(self, vx: float, vy: float, omega: float) -> None:
        self.cmd = np.array([vx, vy, omega], dtype=float)

    def odometry(self) -> Odometry:
        return Odometry(self.world.clock.now(), self.odom_pose, *self.vel)

    def _integrate(self, dt: float) -> None:
        g = self.world.geometry
        # the base ramps like the Robotino host driver
        dv = self.cmd[:2] - self.vel[:2]
        speeding_up = np.linalg.norm(self.cmd[:2]) > np.linalg.norm(self.vel[:2])
        a = (g.max_accel if speeding_up else g.max_decel) * dt
        n = np.linalg.norm(dv)
        self.vel[:2] += dv if n <= a else dv * (a / n)
        dw = self.cmd[2] - self.vel[2]
        self.vel[2] += float(np.clip(dw, -g.max_alpha * dt * 2, g.max_alpha * dt * 2))
        speed = np.linalg.norm(self.vel[:2])
        if speed > g.max_speed:
            self.vel[:2] *= g.max_speed / speed
        step = Pose2D(self.vel[0] * dt, self.vel[1] * dt, self.vel[2] * dt)
        new = self.true_pose.compose(step)
        before = self.world.penetration(self.true_pose, self.index)
        after = self.world.penetration(new, self.index)
        if after <= 0.0 or after < before:       # free, or getting out of contact
            self.true_pose = new
            self.in_contact = False
            nt, nr = self.world.odom_noise
            rng = self.world.rng
            noisy = Pose2D(step.x * (1.0 + rng.normal(0.0, nt)), step.y * (1.0 + rng.normal(0.0, nt)),
                           step.theta * (1.0 + rng.normal(0.0, nr)))
            self.odom_pose = self.odom_pose.compose(noisy)
        elif np.linalg.norm(self.vel) > 1e-6:
            if not self.in_contact:          # count each contact once
                self.collisions += 1
                self.world.collisions += 1
            self.in_contact = True
            self.vel[:] = 0.0
        self._advance_gripper(dt)

    # -- sensors ----------------------------------------------------------
    def laser_scan(self) -> LaserScan:
        now = self.world.clock.now()
        if self._scan_cache is not None and self._scan_cache[0] == now:
            return self._scan_cache[1]
        n = self.laser_beams
        inc = self.laser_fov / (n - 1)
        angles = -self.laser_fov / 2.0 + inc * np.arange(n)
        ranges = self.world.scan(self, angles, self.laser_mount, self.range_max)
        scan = LaserScan(now, -self.laser_fov / 2.0, inc, self.world.geometry.laser_range[0],
                         self.range_max, ranges, self.laser_mount)
        self._scan_cache = (now, scan)
        return scan

    def detections(self, camera: str = "front") -> Detections:
        g, ext = self.world.geometry, self.extrinsics
        cam_pos = self.true_pose.compose(Pose2D(ext.position[0], ext.position[1], 0.0))
        c, s = math.cos(self.true_pose.theta), math.sin(self.true_pose.theta)
        r_robot = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
        r_fo = r_robot @ ext.rotation()                     # optical -> field
        p_cam = np.array([cam_pos.x, cam_pos.y, ext.position[2]])
        tags = []
        for st in self.world.stations.values():
            for side, tag_id in (("INPUT", st.input_tag), ("OUTPUT", st.output_tag)):
                tp = st.tag_pose(side, self.world.mps)
                p_tag = np.array([tp.x, tp.y, self.world.mps.tag_centre_height])
                rel = p_tag - p_cam
                dist = float(np.linalg.norm(rel))
                bearing = wrap_angle(math.atan2(rel[1], rel[0]) - self.true_pose.theta)
                n = np.array([math.cos(tp.theta), math.sin(tp.theta), 0.0])
                facing = -float(n[:2] @ rel[:2]) / max(float(np.linalg.norm(rel[:2])), 1e-9)
                if dist > g.camera_range or abs(bearing) > g.camera_hfov / 2.0 or facing < 0.3:
                    continue
                los = cast_rays(np.array([cam_pos.x, cam_pos.y]), np.array([math.atan2(rel[1], rel[0])]),
                                self.world._segments, 20.0)[0]
                if los < np.linalg.norm(rel[:2]) - 0.02:
                    continue
                up = np.array([0.0, 0.0, 1.0])
                r_ft = np.column_stack([np.cross(up, n), up, n])      # tag axes in the field
                r_ot = r_fo.T @ r_ft
                tvec = r_fo.T @ rel
                if self.tag_noise:
                    tvec = tvec + self.world.rng.normal(0.0, self.tag_noise * dist, 3)
                rvec = cv2.Rodrigues(r_ot)[0].ravel()
                tags.append(TagDetection(tag_id, tuple(map(float, tvec)), tuple(map(float, rvec))))
        return Detections(self.world.clock.now(), tuple(tags), (), ext)

    # -- gripper ----------------------------------------------------------
    def gripper_move(self, x: float, y: float, z: float) -> None:
        for name, v, (lo, hi) in (("x", x, (0.0, 0.15)), ("y", y, (-0.1, 0.1)), ("z", z, (0.0, 1.0))):
            if not lo - 1e-9 <= v <= hi + 1e-9:
                raise BackendError(f"gripper {name}={v:.3f} m is outside {lo}..{hi} m")
        self.gripper.queue.append(("move", (x, y, z)))

    def gripper_open(self) -> None:
        self.gripper.queue.append(("open",))

    def gripper_close(self) -> None:
        self.gripper.queue.append(("close",))

    def gripper_status(self) -> GripperStatus:
        gr = self.gripper
        return GripperStatus(GripperState.MOVING if gr.busy else GripperState.IDLE, gr.is_open,
                             tuple(map(float, gr.pos)), gr.holding is not None,
                             sensed=gr.holding is not None or self._within_grip() is not None)

    def _within_grip(self):
        """The workpiece a close would take now (the gripper's workpiece sensor)."""
        gx, gy, gz = self.gripper_point()
        return next((wp for wp in self.world.workpieces
                     if wp.held_by is None and math.hypot(wp.x - gx, wp.y - gy) <= self.world.grab_tolerance
                     and abs(wp.z + 0.0225 / 2.0 - gz) <= self.world.grab_tolerance), None)

    def gripper_point(self) -> tuple[float, float, float]:
        p = self.true_pose.compose(Pose2D(self.world.geometry.gripper_reach + self.gripper.pos[0],
                                          self.gripper.pos[1], 0.0))
        return p.x, p.y, float(self.gripper.pos[2])

    def _advance_gripper(self, dt: float) -> None:
        gr = self.gripper
        for action in gr.advance(self.world.clock.now(), dt):
            gx, gy, gz = self.gripper_point()
            if action == "close" and gr.holding is None:
                wp = self._within_grip()
                if wp is not None and self.world.fail_next_grab:
                    self.world.fail_next_grab = False
                elif wp is not None:
                    wp.held_by = self.index
                    gr.holding = wp
            elif action == "open" and gr.holding is not None:
                gr.holding.x, gr.holding.y, gr.holding.z = gx, gy, gz - 0.0225 / 2.0
                gr.holding.held_by = None
                gr.holding = None
        if gr.holding is not None:
            gx, gy, gz = self.gripper_point()
            gr.holding.x, gr.holding.y, gr.holding.z = gx, gy, gz - 0.0225 / 2.0
