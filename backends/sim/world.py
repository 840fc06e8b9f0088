"""The PyBullet RCLL world: field, stations, workpieces and robots on one
simulated clock.  See the package docstring (:mod:`backends.sim`) for the
API the simulated referee box, the skills' tests and the game runner use.

Frames and units: the field frame of the rules profile (metres, radians,
z up); time is the world's :class:`~rll_bt.clock.SimClock`, advanced only by
:meth:`World.step`.  The world is deterministic for a seed: the same seed and
the same calls give bit-identical trajectories and sensor noise.
"""
from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np

from rll_bt import rules
from rll_bt.backend import Pose2D
from rll_bt.clock import SimClock
from rll_bt.rules import TEAMS, Profile

from . import oracle, sensors
from .bullet import (
    ShapeCache,
    box_polygon,
    circle_polygon,
    connect,
    prism_mesh,
    pybullet,
    trimesh_shape,
    yaw_quaternion,
)
from .camera import CameraViews
from .collide import Box2D, ObstacleGrid
from .fieldgeom import WALL_HEIGHT, floor_rect, start_pose, walls
from .handling import GripperHandling
from .layout import FieldLayout, generate_layout
from .robot import Collision, RobotConfig, SimRobot
from .stationapi import SlotEvent, StationAPI
from .stations import Station
from .store import WorkpieceStore

PERCEPTION_MODES = ("oracle", "rendered")
STATION_GROUP = 1
ROBOT_COLORS = {"CYAN": (0.1, 0.8, 0.9, 1.0), "MAGENTA": (0.9, 0.2, 0.7, 1.0)}
MAST_RADIUS, MAST_TOP, MAST_X = 0.10, 1.0, -0.05
CONTACT_GAP = 0.005          # a bumper feels anything closer than this, metres
GRID_PAD = 0.5               # largest robot radius the collision grid serves, metres


class World(StationAPI, GripperHandling, CameraViews):
    """See the module and package docstrings."""

    def __init__(self, profile: str | Profile | None = None, seed: int = 0, *,
                 layout: FieldLayout | None = None, perception: str = "oracle",
                 time_step: float = 0.02, clock: SimClock | None = None, gui: bool = False,
                 robot_config: RobotConfig | None = None, blink_hz: float = 2.0,
                 texture_dir: str | None = None):
        if perception not in PERCEPTION_MODES:
            raise ValueError(f"perception must be one of {', '.join(PERCEPTION_MODES)}, not {perception!r}")
        if not time_step > 0:
            raise ValueError(f"time_step must be positive, not {time_step}")
        self.profile = profile if isinstance(profile, Profile) else rules.profile(profile)
        self.seed = int(seed)
        self.layout = layout if layout is not None else generate_layout(self.profile, self.seed)
        if layout is not None and layout.profile != self.profile.name:
            raise ValueError(f"layout is for {layout.profile}, the world plays {self.profile.name}")
        self.perception = perception
        self.time_step = float(time_step)
        self.clock = clock or SimClock()
        self.gui = gui
        self.blink_hz = blink_hz
        self.robot_config = robot_config or RobotConfig()
        self.robots: dict[tuple[str, int], SimRobot] = {}
        self.collision_log: list[Collision] = []
        self._listeners: list[Callable[[SlotEvent], None]] = []
        self._events: list[SlotEvent] = []
        self._synced: dict[int, Pose2D] = {}
        self._closed = False
        self.cid = connect(gui)
        p = pybullet()
        if gui:
            p.configureDebugVisualizer(p.COV_ENABLE_GUI, 0, physicsClientId=self.cid)
            f = self.profile.field
            p.resetDebugVisualizerCamera(cameraDistance=max(f.x_max - f.x_min, 8.0) * 0.8, cameraYaw=0,
                                         cameraPitch=-65, cameraTargetPosition=[0, f.centre[1], 0],
                                         physicsClientId=self.cid)
        self._shapes = ShapeCache(self.cid)
        self._build_floor_and_walls()
        self.stations: dict[str, Station] = {}
        for name in self.layout:
            st = Station(self.profile, self.layout[name])
            st.build(self.cid, self._shapes, texture_dir)
            p.setCollisionFilterGroupMask(st.body, -1, STATION_GROUP, sensors.ALL_GROUPS,
                                          physicsClientId=self.cid)
            self.stations[name] = st
        self._station_list = [self.stations[n] for n in sorted(self.stations)]
        self._body_station = {st.body: st.name for st in self._station_list}
        self._obstacles = [(st.name, st.box) for st in self._station_list]
        self._obstacles += [("wall", b) for b in self._wall_boxes]
        self._grid = ObstacleGrid(self._obstacles, pad=GRID_PAD)
        self.store = WorkpieceStore(self.cid, self._shapes, self.stations)
        self._oracle = oracle.OracleScene(self._station_list, self.profile.tag_size)

    # -- construction -------------------------------------------------------
    def _build_floor_and_walls(self) -> None:
        p = pybullet()
        fr = floor_rect(self.profile)
        half = ((fr.x_max - fr.x_min) / 2, (fr.y_max - fr.y_min) / 2, 0.005)
        p.createMultiBody(0, -1, self._shapes.box(half, (0.55, 0.57, 0.55, 1.0)),
                          basePosition=[fr.centre[0], fr.centre[1], -0.005], physicsClientId=self.cid)
        self._wall_boxes = []
        for r in walls(self.profile):
            half = ((r.x_max - r.x_min) / 2, (r.y_max - r.y_min) / 2, WALL_HEIGHT / 2)
            col = trimesh_shape(self.cid, [prism_mesh(box_polygon(half[0], half[1]), -half[2], half[2])])
            body = p.createMultiBody(0, col, self._shapes.box(half, (0.92, 0.92, 0.9, 1.0)),
                                     basePosition=[r.centre[0], r.centre[1], WALL_HEIGHT / 2],
                                     physicsClientId=self.cid)
            p.setCollisionFilterGroupMask(body, -1, STATION_GROUP, sensors.ALL_GROUPS,
                                          physicsClientId=self.cid)
            self._wall_boxes.append(Box2D.from_rect(r.x_min, r.y_min, r.x_max, r.y_max))

    def _robot_body(self, robot: SimRobot) -> int:
        p = pybullet()
        g = robot.config.geometry
        kw = {"shapeTypes": [p.GEOM_CYLINDER, p.GEOM_CYLINDER], "radii": [g.radius, MAST_RADIUS],
                  "lengths": [g.height, MAST_TOP - g.height]}
        frames = [[0.0, 0.0, g.height / 2], [MAST_X, 0.0, (g.height + MAST_TOP) / 2]]
        col = trimesh_shape(self.cid, [prism_mesh(circle_polygon(g.radius), 0.0, g.height),
                                       prism_mesh(circle_polygon(MAST_RADIUS, 12, MAST_X), g.height, MAST_TOP)])
        vis = p.createVisualShapeArray(visualFramePositions=frames, physicsClientId=self.cid, **kw)
        body = p.createMultiBody(0.0, col, vis, basePosition=[robot.pose.x, robot.pose.y, 0.0],
                                 baseOrientation=yaw_quaternion(robot.pose.theta), physicsClientId=self.cid)
        p.changeVisualShape(body, -1, rgbaColor=list(ROBOT_COLORS.get(robot.team, (0.5, 0.5, 0.5, 1))),
                            physicsClientId=self.cid)
        p.setCollisionFilterGroupMask(body, -1, robot.ray_group, sensors.ALL_GROUPS, physicsClientId=self.cid)
        self._synced[body] = robot.pose
        return body

    # -- time ---------------------------------------------------------------
    @property
    def time(self) -> float:
        """Sim time in seconds (the clock's ``now()``)."""
        return self.clock.now()

    def step(self, dt: float | None = None) -> float:
        """Advance the world by ``dt`` seconds (default one ``time_step``),
        in equal sub-steps no longer than ``time_step``.  Returns the new time."""
        if dt is None:
            n, h = 1, self.time_step
        else:
            if dt < 0:
                raise ValueError(f"cannot step backwards ({dt})")
            if dt == 0:
                return self.time
            n = max(1, math.ceil(dt / self.time_step - 1e-9))
            h = dt / n
        for _ in range(n):
            self._substep(h)
        return self.time

    def run(self, seconds: float, callback: Callable[[float], None] | None = None) -> float:
        """Step ``seconds`` in ``time_step`` increments, calling ``callback(t)``
        after each; returns the new time."""
        end = self.time + seconds
        while self.time < end - 1e-9:
            self.step(min(self.time_step, end - self.time))
            if callback:
                callback(self.time)
        return self.time

    def _substep(self, h: float) -> None:
        now = self.time
        for key in sorted(self.robots):
            self._move(self.robots[key], h, now)
        self.clock.advance(h)
        t = self.time
        for key in sorted(self.robots):
            r = self.robots[key]
            for action in r.gripper.update(t):
                (self._grab if action == "close" else self._release)(r)
            if r.holding is not None:
                self.store.move(r.holding, self.gripper_point(r, bottom=True))
        if self.gui:
            self._sync_bodies()
            self._show_lights()
        self._fire_events()

    # -- robots -------------------------------------------------------------
    def add_robot(self, team: str, number: int, pose: Pose2D | None = None,
                  config: RobotConfig | None = None, **options) -> SimRobot:
        """Put robot ``number`` of ``team`` on the field (default: its lane
        in the team's insertion area, facing into the field).  ``options``
        override fields of the world's :class:`RobotConfig`."""
        team = team.upper()
        if team not in TEAMS:
            raise ValueError(f"team must be CYAN or MAGENTA, not {team!r}")
        key = (team, int(number))
        if key in self.robots:
            raise ValueError(f"robot {team}/{number} is already in the world")
        cfg = (config or self.robot_config).with_options(**options)
        if cfg.geometry.radius > GRID_PAD:
            raise ValueError(f"robot radius {cfg.geometry.radius} m exceeds the supported {GRID_PAD} m")
        pose = pose or start_pose(self.profile, team, key[1])
        seq = np.random.SeedSequence([self.seed, TEAMS.index(team), key[1]])
        robot = SimRobot(team, key[1], pose, cfg, np.random.default_rng(seq),
                         ray_group=1 << (1 + len(self.robots) % 30), born=self.time)
        robot.body = self._robot_body(robot)
        self.robots[key] = robot
        return robot

    def robot(self, team: str, number: int) -> SimRobot:
        try:
            return self.robots[(team.upper(), int(number))]
        except KeyError:
            raise KeyError(f"no robot {team}/{number} in the world "
                           f"(robots: {', '.join(r.name for r in self.robots.values()) or 'none'})") from None

    def robot_pose(self, team: str, number: int) -> Pose2D:
        """Ground-truth pose in the field frame (for tests and the refbox)."""
        return self.robot(team, number).pose

    def teleport(self, team: str, number: int, pose: Pose2D) -> None:
        """Set a robot's true pose (velocity and drive command zeroed;
        odometry untouched)."""
        r = self.robot(team, number)
        r.pose, r.velocity = pose, (0.0, 0.0, 0.0)
        r.stop(self.time)
        if r.holding is not None:
            self.store.move(r.holding, self.gripper_point(r, bottom=True))

    @property
    def collision_count(self) -> int:
        """Collision events of all robots so far."""
        return sum(r.collisions for r in self.robots.values())

    def _move(self, r: SimRobot, h: float, now: float) -> None:
        if r.touching:
            self._separate(r)
        pose, vel = r.propose(h, now)
        if pose is r.pose:
            r.commit(pose, vel, h)
            r.blocked = False
            return
        hit = self._blocker(r, pose)
        if hit is None:
            r.commit(pose, vel, h)
            r.blocked = False
            return
        # advance to the contact point by bisection (unless already pressing against it), then stop
        lo, hi, start = 0.0, 1.0, r.pose
        for _ in range(0 if r.blocked else 6):
            mid = (lo + hi) / 2
            cand = Pose2D(start.x + (pose.x - start.x) * mid, start.y + (pose.y - start.y) * mid,
                          start.theta)
            if self._blocker(r, cand) is None:
                lo = mid
            else:
                hi = mid
        stop = start if lo == 0.0 else Pose2D(start.x + (pose.x - start.x) * lo,
                                              start.y + (pose.y - start.y) * lo, start.theta)
        speed = math.hypot(r.velocity[0], r.velocity[1])
        if r.config.odom_slip:          # the wheels keep turning
            r.commit(stop, vel, h, wheels=pose.relative_to(start))
        else:
            r.commit(stop, (0.0, 0.0, 0.0), h)
        if hit not in r.touching:       # a new contact, not more pushing against the same thing
            r.touching.add(hit)
            if not self._same_contact(r, hit):
                r.collisions += 1
                self.collision_log.append(Collision(now, r.key, hit, stop, speed))
        r.blocked = True
        r.blocked_steps += 1

    def _same_contact(self, r: SimRobot, hit: str) -> bool:
        """Two robots touching are one collision, whichever pushes first or
        both: ``r`` blocked by robot ``hit`` that already touches it (it ran
        into ``r``, or they have stood pressed together since) adds none."""
        if not hit.startswith("robot "):
            return False
        team, number = hit[len("robot "):].split("/")
        other = self.robots.get((team, int(number)))
        return other is not None and f"robot {r.name}" in other.touching

    def _separate(self, r: SimRobot) -> None:
        """Forget the contacts the robot has left (gap above ``CONTACT_GAP``)."""
        for name in list(r.touching):
            if name.startswith("robot "):
                team, number = name[len("robot "):].split("/")
                other = self.robots.get((team, int(number)))
                gap = math.inf if other is None else \
                    math.hypot(r.pose.x - other.pose.x, r.pose.y - other.pose.y) - r.radius - other.radius
            else:
                gap = min((box.sdf(r.pose.x, r.pose.y) - r.radius for n, box in self._obstacles if n == name),
                          default=math.inf)
            if gap > CONTACT_GAP:
                r.touching.discard(name)

    def _blocker(self, r: SimRobot, pose: Pose2D) -> str | None:
        """What would overlap ``r`` at ``pose`` more than at its current pose."""
        x, y, rad = pose.x, pose.y, r.radius
        ox, oy = r.pose.x, r.pose.y
        for name, box in self._grid.near(x, y):
            gap = box.sdf(x, y) - rad
            if gap < 0.0 and gap < box.sdf(ox, oy) - rad - 1e-9:
                return name
        for other in self.robots.values():
            if other is r:
                continue
            reach = rad + other.radius
            dx, dy = x - other.pose.x, y - other.pose.y
            if abs(dx) > reach or abs(dy) > reach:
                continue
            gap = math.hypot(dx, dy) - reach
            if gap < 0.0 and gap < math.hypot(ox - other.pose.x, oy - other.pose.y) - reach - 1e-9:
                return f"robot {other.name}"
        return None

    def clearance(self, team: str, number: int) -> float:
        """Smallest gap between the robot and any wall, station or robot (metres)."""
        return self.closest(team, number)[0]

    def closest(self, team: str, number: int) -> tuple[float, str]:
        """(gap in metres, what) of the wall, station or robot nearest to the
        robot; ``what`` is a machine name, "wall" or "robot TEAM/N"."""
        r = self.robot(team, number)
        gaps = [(box.sdf(r.pose.x, r.pose.y) - r.radius, name) for name, box in self._obstacles]
        gaps += [(math.hypot(r.pose.x - o.pose.x, r.pose.y - o.pose.y) - r.radius - o.radius, f"robot {o.name}")
                 for o in self.robots.values() if o is not r]
        return min(gaps, key=lambda g: g[0])

    def bumper(self, robot: SimRobot) -> bool:
        """Pressed while the robot pushes against something or touches it."""
        return robot.blocked or self.clearance(robot.team, robot.number) < CONTACT_GAP

    # -- sensors ------------------------------------------------------------
    def _sync_bodies(self) -> None:
        """Move robot bodies to their poses (done lazily: before rays, renders, GUI frames)."""
        p = pybullet()
        for r in self.robots.values():
            if self._synced.get(r.body) is not r.pose:
                p.resetBasePositionAndOrientation(r.body, [r.pose.x, r.pose.y, 0.0],
                                                  yaw_quaternion(r.pose.theta), physicsClientId=self.cid)
                self._synced[r.body] = r.pose

    def _show_lights(self) -> None:
        for st in self._station_list:
            st.show_lights(self.cid, self.time, self.blink_hz)

    def laser_scan(self, robot: SimRobot):
        """The robot's scan, at most ``laser_rate`` new scans per second."""
        last = robot.last_scan
        if last is not None and self.time - last.stamp < 1.0 / robot.config.laser_rate - 1e-9:
            return last
        self._sync_bodies()
        others = frozenset(r.body for r in self.robots.values() if r is not robot)
        robot.last_scan = sensors.laser_scan(self.cid, robot, self.time, others)
        return robot.last_scan

    def laser_sightings(self) -> dict[str, dict[str, int]]:
        """Per robot ("TEAM/N"), the other robots its laser scans have hit: robot -> scans."""
        name = {r.body: r.name for r in self.robots.values()}
        return {r.name: {name[b]: n for b, n in sorted(r.laser_hits.items(), key=lambda kv: name[kv[0]])}
                for r in sorted(self.robots.values(), key=lambda r: r.name) if r.laser_hits}

    def detections(self, robot: SimRobot, camera: str = "front"):
        """Oracle detections (works in either mode; the backend exposes it only in oracle mode)."""
        self._sync_bodies()
        return self._oracle.detect(self.cid, robot, self.time, self.blink_hz, camera)

    def ray(self, start, end, ignore: SimRobot | None = None) -> tuple[str | None, float]:
        """What a straight line hits first: (machine name, "wall", "robot T/N"
        or None, distance in metres)."""
        self._sync_bodies()
        hit = pybullet().rayTestBatch([list(start)], [list(end)], numThreads=1,
                                      collisionFilterMask=sensors.ray_mask(ignore),
                                      physicsClientId=self.cid)[0]
        length = float(np.linalg.norm(np.subtract(end, start)))
        if hit[0] < 0:
            return None, math.inf
        name = self._body_station.get(hit[0])
        if name is None:
            name = next((f"robot {r.name}" for r in self.robots.values() if r.body == hit[0]), "wall")
        return name, hit[2] * length

    # -- life cycle ---------------------------------------------------------
    @property
    def connected(self) -> bool:
        if self._closed:
            return False
        return bool(pybullet().getConnectionInfo(physicsClientId=self.cid)["isConnected"])

    def close(self) -> None:
        if not self._closed:
            self._closed = True
            try:
                pybullet().disconnect(physicsClientId=self.cid)
            except Exception:      # already gone (GUI window closed by the user)
                pass

    def __enter__(self) -> World:
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def __del__(self):
        try:
            self.close()
        except Exception:
            pass
