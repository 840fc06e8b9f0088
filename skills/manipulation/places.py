"""Where at a station the robot picks or places, and how the gripper reaches it.

A *place* is a face (``INPUT``/``OUTPUT``) plus a spot on it: ``conveyor``
(the belt end), ``shelf0..2`` (a cap station's shelf, input face) or
``slide`` (a ring station's slide, input face).  The team protocol's
``MachineSide`` (INPUT, OUTPUT, SHELF, SLIDE) maps onto it with
:func:`place_for`.
"""
from __future__ import annotations

from dataclasses import dataclass

from rll_bt.rules import Profile

from ..errors import SkillError, SkillFailure
from ..navigation.goals import side_sign, target_lateral


@dataclass(frozen=True)
class Place:
    machine: str
    side: str            # INPUT / OUTPUT
    spot: str = "conveyor"

    def describe(self) -> str:
        return f"{self.machine} {self.side.lower()} {self.spot}"


def place_for(machine: str, side: str, shelf_slot: int | None = None) -> Place:
    """A place from the team protocol's side name: INPUT, OUTPUT, SHELF
    (with ``shelf_slot`` 0..2) or SLIDE."""
    s = side.upper()
    if s in ("INPUT", "OUTPUT"):
        return Place(machine, s, "conveyor")
    if s == "SHELF":
        if shelf_slot is None:
            raise SkillFailure(SkillError.INVALID_TASK, f"{machine}: SHELF needs a shelf slot (0..2)")
        return Place(machine, "INPUT", f"shelf{int(shelf_slot)}")
    if s == "SLIDE":
        return Place(machine, "INPUT", "slide")
    raise SkillFailure(SkillError.INVALID_TASK, f"unknown machine side {side!r} (INPUT, OUTPUT, SHELF, SLIDE)")


def check_place(place: Place, profile: Profile) -> None:
    """Fail with INVALID_TASK when the place does not exist at that station."""
    try:
        profile.tag_ids(place.machine)
        side_sign(place.side)
        target_lateral(place.spot, profile.mps)
    except ValueError as exc:
        raise SkillFailure(SkillError.INVALID_TASK, str(exc)) from None
    kind = place.machine[2:4]
    if place.spot.startswith("shelf") and kind != "CS":
        raise SkillFailure(SkillError.INVALID_TASK, f"{place.machine} has no shelf")
    if place.spot == "slide" and kind != "RS":
        raise SkillFailure(SkillError.INVALID_TASK, f"{place.machine} has no slide")
    if place.machine[2:4] == "DS" and place.side == "OUTPUT":
        raise SkillFailure(SkillError.INVALID_TASK, f"{place.machine} has no output")


def lateral_offset(place: Place, profile: Profile) -> float:
    """The spot's offset from the tag along the face, in the tag's 2D frame
    (x out of the face, y to its left as the face sees it), metres."""
    mps = profile.mps
    return side_sign(place.side) * (target_lateral(place.spot, mps) - mps.belt_offset_y)


def gripper_target(profile: Profile, final_distance: float, slot_inset: float) -> tuple[float, float, float]:
    """Gripper axes (x forward beyond the reach, y, z height) that put the
    gripper point on a slot's workpiece when the robot stands
    ``final_distance`` from the face, squarely in front of the spot."""
    x = final_distance + slot_inset - profile.robot.gripper_reach
    if not 0.0 <= x <= 0.15:
        raise SkillFailure(SkillError.INVALID_TASK,
                           f"the gripper cannot reach {slot_inset:.2f} m into the station from "
                           f"{final_distance:.2f} m (needs x = {x:.3f} m, range 0..0.15)")
    return x, 0.0, gripper_height(profile)


def gripper_height(profile: Profile) -> float:
    """Gripper height for a base standing on the belt, shelf or slide."""
    return profile.mps.belt_height + profile.workpiece.base_height / 2.0
