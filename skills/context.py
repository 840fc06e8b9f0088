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
from dataclasses import dataclass, field
from typing import Protocol, runtime_checkable

from rll_bt.backend import Backend, BackendError, Pose2D
from rll_bt.clock import Clock
from rll_bt.rules import Profile

from .localisation import AmclConfig, Localiser, PoseEstimate
from .machines import BackendTagSource, MachineMap, TagSource
from .maps import FieldMap
from .navigation.costmap import Costmap


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
        return self.start.compose(self.backend.odometry().pose.relative_to(self.odom0))

    def estimate(self) -> None:
        return None


@dataclass
class SkillSettings:
    """Limits and tolerances shared by the skills (SI units)."""
    max_speed: float = 0.7            # m/s, the rules' limit
    max_omega: float = 1.6            # rad/s
    max_accel: float = 0.8            # m/s^2
    max_decel: float = 1.2            # m/s^2, planned; the base can do 1.5
    max_alpha: float = 1.6            # rad/s^2
    control_period: float = 0.1       # s, the expected time between polls
    position_tolerance: float = 0.05  # m, a navigation goal is reached
    heading_tolerance: float = 0.05   # rad
    safety_margin: float = 0.08       # m, kept free around the robot by the laser check
    blind_speed: float = 0.2          # m/s, top speed toward where the laser cannot see
    plan_padding: float = 0.05        # m, added to the robot radius in the costmap
    costmap_resolution: float = 0.05  # m
    obstacle_ttl: float = 4.0         # s, laser obstacles stay in the costmap
    block_replan_after: float = 1.0   # s blocked before replanning around it
    require_localisation: float = 0.0   # minimum confidence to drive (0: do not check)
    extra: dict = field(default_factory=dict)


class SkillContext:
    def __init__(self, backend: Backend, clock: Clock, profile: Profile, field_map: FieldMap,
                 pose_source: PoseSource, machines: MachineMap | None = None,
                 tags: TagSource | None = None, settings: SkillSettings | None = None):
        self.backend = backend
        self.clock = clock
        self.profile = profile
        self.map = field_map
        self.pose_source = pose_source
        self.machines = machines or MachineMap(field_map, profile.mps)
        self.tags = tags or BackendTagSource(backend)
        self.settings = settings or SkillSettings(max_speed=profile.robot.max_speed)
        self.robot = profile.robot
        self._updated_at: float | None = None
        self._costmap: Costmap | None = None

    @classmethod
    def create(cls, backend: Backend, clock: Clock, profile: Profile, start: Pose2D,
               localisation: str | AmclConfig | None = "standard", seed: int = 0,
               field_map: FieldMap | None = None, **kw) -> "SkillContext":
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

    def pose(self) -> Pose2D:
        pose = self.pose_source.pose()
        if pose is None:
            raise RuntimeError("the pose source has no pose yet")
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
            self._costmap = Costmap(self.map, s.costmap_resolution, self.robot.radius, s.plan_padding)
        return self._costmap

    def heading_to(self, x: float, y: float) -> float:
        p = self.pose()
        return math.atan2(y - p.y, x - p.x)
