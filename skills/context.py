"""What every skill of one robot shares: the backend, the clock, the rules
profile, the known map, the pose source, the station knowledge and the
settings.

    ctx = SkillContext.create(backend, clock, rules.profile("rcll2016"),
                              start=Pose2D(4.5, -0.5, math.pi / 2), localisation="cheap")
    nav = Navigate(ctx, PoseGoal(Pose2D(1.0, 2.0, 0.0))).start()
    while nav.poll() is Status.RUNNING: ...

``ctx.update()`` runs once per clock instant however many activities poll
it (nested activities do): it advances the localiser and drops expired
temporary obstacles.
"""
from __future__ import annotations

import math
from typing import Protocol, runtime_checkable

from rll_bt.backend import Backend, BackendError, Pose2D
from rll_bt.clock import Clock
from rll_bt.rules import Profile

from .errors import NotLocalised
from .localisation import AmclConfig, Localiser, PoseEstimate
from .machines import MachineMap, TagSource
from .maps import FieldMap
from .navigation.costmap import Costmap
from .navigation.laserview import LaserMemory, OdometryHistory
from .settings import ManipulationSettings, SkillSettings  # noqa: F401  (re-exported)


@runtime_checkable
class PoseSource(Protocol):
    def pose(self) -> Pose2D | None: ...
    def update(self) -> object: ...
    @property
    def confidence(self) -> float: ...
    @property
    def lost(self) -> bool: ...


class OdometryPose:
    """Dead reckoning as a pose source: the field pose is ``start`` composed
    with the odometry since creation.  For backends whose odometry is good
    enough (ground truth in tests) or when no laser exists."""

    def __init__(self, backend: Backend, start: Pose2D):
        self.backend = backend
        self.start = start
        self.odom0 = backend.odometry().pose
        self.confidence = 1.0
        self.lost = False

    def update(self) -> bool:
        return False

    def pose(self) -> Pose2D:
        return self.pose_with(self.backend.odometry().pose)

    def pose_with(self, odom: Pose2D) -> Pose2D:
        return self.start.compose(odom.relative_to(self.odom0))

    def estimate(self) -> None:
        return None


class FunctionPose:
    """A pose source that asks a function (a simulator's ground truth in
    tests and benchmarks, or an external localisation system)."""

    def __init__(self, fn, confidence: float = 1.0):
        self.fn = fn
        self.confidence = confidence
        self.lost = False

    def update(self) -> bool:
        return False

    def pose(self) -> Pose2D:
        return self.fn()


class SkillContext:
    def __init__(self, backend: Backend, clock: Clock, profile: Profile, field_map: FieldMap,
                 pose_source: PoseSource, machines: MachineMap | None = None,
                 tags: TagSource | None = None, settings: SkillSettings | None = None,
                 robot_number: int = 0):
        self.backend = backend
        self.robot_number = robot_number      # the robot's number in its team (0: not known); ranks giving way
        self.clock = clock
        self.profile = profile
        self.map = field_map
        self.pose_source = pose_source
        self.machines = machines or MachineMap(field_map, profile.mps)
        if tags is None:
            # the simulator's oracle when the backend reports detections itself,
            # otherwise the detectors on its camera frames: a setting, not a code path
            from .perception.source import make_tag_source
            tags = make_tag_source(backend, profile)
        self.tags = tags
        self.settings = settings or SkillSettings(max_speed=profile.robot.max_speed)
        self.robot = profile.robot
        self._updated_at: float | None = None
        self._costmap: Costmap | None = None
        self.odometry_history = OdometryHistory()
        self.laser_memory = LaserMemory()
        #: place (``Place.describe()``) -> metres the robot's docked sideways move to it stopped
        #: short of where it meant to stand: the gripper reaches over them (skills.manipulation)
        self.short_of_spot: dict[str, float] = {}

    @classmethod
    def create(cls, backend: Backend, clock: Clock, profile: Profile, start: Pose2D,
               localisation: str | AmclConfig | None = "standard", seed: int = 0,
               field_map: FieldMap | None = None, **kw) -> SkillContext:
        """A context with a localiser (preset name or config) started at
        ``start``, or dead reckoning when ``localisation`` is None."""
        fmap = field_map or FieldMap.from_profile(profile)
        if localisation is None:
            source: PoseSource = OdometryPose(backend, start)
        else:
            cfg = localisation if isinstance(localisation, AmclConfig) else AmclConfig.preset(localisation)
            source = Localiser(backend, fmap, clock, cfg, seed)
            source.initialise(start, (0.1, 0.1, 0.1))
        return cls(backend, clock, profile, fmap, source, **kw)

    # -- per tick ---------------------------------------------------------
    def update(self) -> None:
        now = self.clock.now()
        if self._updated_at == now:
            return
        self._updated_at = now
        self.pose_source.update()
        odom = self.backend.odometry()
        self.odometry_history.add(odom.stamp, odom.pose)

    def pose(self) -> Pose2D:
        pose = self.pose_source.pose()
        if pose is None:
            raise NotLocalised()
        return pose

    def pose_at(self, stamp: float) -> Pose2D:
        """The pose at ``stamp`` (a sensor reading's time, e.g. of a camera
        frame): the pose for the odometry of that moment, interpolated
        between the readings recorded around it.  A reading's stamp and the
        odometry read after it differ by a call to the robot (over a
        network, with a loaded host, by tenths of a second, while the robot
        turns): a tag seen then and placed from the pose now lands beside
        where it is.  The pose now when ``stamp`` is not covered or the
        pose source cannot say."""
        pose_with = getattr(self.pose_source, "pose_with", None)
        if pose_with is None:
            return self.pose()
        reading = self.backend.odometry()
        self.odometry_history.add(reading.stamp, reading.pose)
        then = self.odometry_history.interpolate(stamp)
        pose = pose_with(reading.pose if then is None else then)
        if pose is None:
            raise NotLocalised()
        return pose

    def estimate(self) -> PoseEstimate | None:
        est = getattr(self.pose_source, "estimate", None)
        return est() if callable(est) else None

    def stop_base(self) -> None:
        try:
            self.backend.stop()
        except BackendError:
            pass

    @property
    def costmap(self) -> Costmap:
        if self._costmap is None:
            s = self.settings
            self._costmap = Costmap(self.map, s.costmap_resolution, self.robot.radius, s.plan_padding,
                                    obstacle_padding=s.obstacle_padding)
        return self._costmap

    def heading_to(self, x: float, y: float) -> float:
        p = self.pose()
        return math.atan2(y - p.y, x - p.x)
