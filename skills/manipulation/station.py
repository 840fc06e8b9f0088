"""Station handling: approach a place, grab from it, put onto it.

- :class:`ApproachStation`: navigate to ``coarse_distance`` in front of the
  place (from the machine map), line up on the tag (when a tag source
  works), dock by laser to ``final_distance``.
- :class:`GrabFrom`: approach, open, reach in, close, pull back, check the
  gripper holds a workpiece (``GRAB_FAILED`` when it does not), back off.
- :class:`PutOnto`: approach, reach in, open, pull back, check the gripper
  is empty (``PUT_FAILED`` when not), back off.

Each is a :class:`~skills.activity.Sequence`; its ``current`` child tells
which phase runs.  ``approach=False`` skips the approach (the robot is
already docked, e.g. on a retry after a failed grab).
"""
from __future__ import annotations

from ..activity import Sequence
from ..errors import SkillError
from ..navigation import Navigate, StationSideGoal
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

        def navigate():
            check_place(place, ctx.profile)
            # in front of the tag (it is centred under the belt), so the camera sees it
            goal = StationSideGoal(place.machine, place.side, m.coarse_distance, "conveyor")
            return Navigate(ctx, goal, position_tolerance=0.03, heading_tolerance=0.04)

        def align():
            use = tags_available(ctx) if self.use_tag is None else self.use_tag
            if use:
                return AlignToTag(ctx, place, m.coarse_distance)
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
    factories.append(lambda: MoveRelative(ctx, -m.back_off, speed=0.2))
    return factories


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
