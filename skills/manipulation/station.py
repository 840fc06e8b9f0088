"""Station handling: approach a place, grab from it, put onto it.

- :class:`ApproachStation`: navigate to ``coarse_distance`` in front of the
  place (from the machine map; closer where a wall or station leaves less
  room), line up on the tag (when a tag source works and the camera can
  see the tag from there, else on the map pose), dock by laser to
  ``final_distance``.
- :class:`GrabFrom`: approach, open, reach in, close, pull back, check the
  gripper holds a workpiece (``GRAB_FAILED`` when it does not), back off.
- :class:`PutOnto`: approach, reach in, open, pull back, check the gripper
  is empty (``PUT_FAILED`` when not), back off.

Each is a :class:`~skills.activity.Sequence`; its ``current`` child tells
which phase runs.  ``approach=False`` skips the approach (the robot is
already docked, e.g. on a retry after a failed grab).
"""
from __future__ import annotations

import numpy as np

from ..activity import Sequence
from ..errors import SkillError
from ..navigation import Navigate, StationSideGoal
from ..navigation.goals import approach_pose, feasible_distance, target_lateral
from ..navigation.motions import MoveRelative
from .align import AlignToTag, Dock
from .gripper import GripperSequence
from .places import Place, check_place, gripper_height, gripper_target, lateral_offset


def tags_available(ctx) -> bool:
    """Whether ``ctx.tags`` can deliver tag sightings at all."""
    ctx.tags.detections()
    return getattr(ctx.tags, "available", True)


class ApproachStation(Sequence):
    def __init__(self, ctx, place: Place, use_tag: bool | None = None, timeout: float | None = None):
        self.place = place
        self.use_tag = use_tag
        m = ctx.settings.manipulation

        self.coarse = m.coarse_distance

        def navigate():
            check_place(place, ctx.profile)
            pose = ctx.machines.get(place.machine)
            if pose is not None:      # less room in front of the station: stop closer
                d = feasible_distance(ctx, pose, place.side, m.coarse_distance, ctx.profile.mps.belt_offset_y)
                self.coarse = m.coarse_distance if d is None else d
            # in front of the tag (it is centred under the belt), so the camera sees it
            goal = StationSideGoal(place.machine, place.side, self.coarse, "conveyor")
            return Navigate(ctx, goal, position_tolerance=0.03, heading_tolerance=0.04)

        def align():
            use = tags_available(ctx) if self.use_tag is None else self.use_tag
            if use and self.use_tag is None and self.coarse < m.tag_min_distance:
                use = False           # too close for the camera to see the tag whole
            if use:
                return AlignToTag(ctx, place, self.coarse)
            # without tags: the navigation pose from the machine map is the alignment
            return MoveRelative(ctx, 0.0, -lateral_offset(place, ctx.profile))

        super().__init__(ctx, [navigate, align, lambda: Dock(ctx, m.final_distance)], timeout,
                         name=f"approach {place.describe()}")


def _handling(ctx, place: Place, steps_fn, approach: bool, use_tag, timeout, name):
    m = ctx.settings.manipulation
    factories = []
    if approach:
        factories.append(lambda: ApproachStation(ctx, place, use_tag))

    def gripper():
        check_place(place, ctx.profile)
        x, y, z = gripper_target(ctx.profile, m.final_distance, m.slot_inset)
        return GripperSequence(ctx, steps_fn(x, y, z), home_z=z, name=name)

    factories.append(gripper)

    def back_off():
        machine = ctx.machines.get(place.machine)
        docked = None
        if machine is not None:       # docked: the station and the laser know where we are
            docked = approach_pose(machine, place.side, m.final_distance,
                                   target_lateral(place.spot, ctx.profile.mps), ctx.profile.mps)
        return MoveRelative(ctx, -back_off_distance(ctx, m.back_off, docked), speed=0.2)

    factories.append(back_off)
    return factories


def back_off_distance(ctx, wanted: float, pose=None, step: float = 0.01) -> float:
    """How far the robot can back straight off from ``pose`` (default: the
    localised pose), at most ``wanted``, at least 5 cm: the laser does not
    see behind, so the known map decides; the robot keeps its radius plus
    5 cm from walls and stations all the way."""
    pose = pose or ctx.pose()
    dist = ctx.map.distance(ctx.settings.costmap_resolution)
    ds = np.arange(step, wanted + 1e-9, step)
    xs = pose.x - np.cos(pose.theta) * ds
    ys = pose.y - np.sin(pose.theta) * ds
    clear = dist.lookup(xs, ys)
    start = float(dist.lookup(np.array([pose.x]), np.array([pose.y]))[0])
    need = min(ctx.robot.radius + 0.05, start)       # docked: the face in front is close
    bad = np.nonzero(clear < need)[0]
    far = ds[bad[0] - 1] if len(bad) and bad[0] > 0 else (0.0 if len(bad) else wanted)
    return float(max(far, 0.05))


class GrabFrom(Sequence):
    """Pick up the workpiece at ``place``; fails with GRAB_FAILED when the
    gripper is empty afterwards."""

    def __init__(self, ctx, place: Place, approach: bool = True, use_tag: bool | None = None,
                 timeout: float | None = None):
        self.place = place

        def steps(x, y, z):
            return [("open",), ("move", x, y, z), ("close",), ("move", 0.0, 0.0, z),
                    ("expect_holding", True, SkillError.GRAB_FAILED)]

        super().__init__(ctx, _handling(ctx, place, steps, approach, use_tag, timeout,
                                        f"grab from {place.describe()}"),
                         timeout, name=f"grab from {place.describe()}")


class PutOnto(Sequence):
    """Put the held workpiece onto ``place``; fails with PUT_FAILED when the
    gripper still holds it afterwards."""

    def __init__(self, ctx, place: Place, approach: bool = True, use_tag: bool | None = None,
                 timeout: float | None = None):
        self.place = place

        def steps(x, y, z):
            return [("move", x, y, z), ("open",), ("move", 0.0, 0.0, z),
                    ("expect_holding", False, SkillError.PUT_FAILED)]

        super().__init__(ctx, _handling(ctx, place, steps, approach, use_tag, timeout,
                                        f"put onto {place.describe()}"),
                         timeout, name=f"put onto {place.describe()}")


def gripper_home(ctx) -> tuple[float, float, float]:
    return 0.0, 0.0, gripper_height(ctx.profile)
