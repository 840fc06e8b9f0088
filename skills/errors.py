"""Failure codes of the skills.

Every name is a value of the team protocol's ``rllbt.ErrorCode``
(``rll_bt/msgs/proto/team/common.proto``), so the mid-level reports a
skill's code to the team server unchanged: ``ErrorCode.Value(err.value)``.
A failed activity carries one code and a message that says what was seen.
"""
from __future__ import annotations

import enum


class SkillError(enum.Enum):
    NONE = "NONE"
    NAVIGATION_FAILED = "NAVIGATION_FAILED"   # no path, or blocked for too long
    LOCALISATION_LOST = "LOCALISATION_LOST"   # pose confidence fell below the limit
    MACHINE_NOT_FOUND = "MACHINE_NOT_FOUND"   # the station's pose or tag is not known / not seen
    ALIGN_FAILED = "ALIGN_FAILED"        # could not line up with the conveyor, shelf or slide
    GRAB_FAILED = "GRAB_FAILED"          # the gripper does not hold a workpiece after a grab
    PUT_FAILED = "PUT_FAILED"            # the gripper still holds the workpiece after a put
    GRIPPER_ERROR = "GRIPPER_ERROR"      # the gripper reported a fault
    TIMEOUT = "TIMEOUT"                  # did not finish within its time limit
    CANCELLED = "CANCELLED"              # stopped by the caller, not a fault
    INVALID_TASK = "INVALID_TASK"        # a goal outside the field, an unknown place
    INTERNAL = "INTERNAL"                # the backend failed in an unexpected way
    SENSOR_LOST = "SENSOR_LOST"          # the laser or camera stopped delivering; the robot stopped


class SkillFailure(Exception):
    """Raised inside an activity step to end it with ``code``."""

    def __init__(self, code: SkillError, message: str):
        super().__init__(f"{code.value}: {message}")
        self.code = code
        self.message = message


class NotLocalised(SkillFailure, RuntimeError):
    """The pose source has no pose (a global search that has not converged,
    e.g. while the laser is away): an activity starting or stepping now ends
    with LOCALISATION_LOST instead of crashing its tree."""

    def __init__(self, message: str = "no pose yet (the localiser is still searching)"):
        super().__init__(SkillError.LOCALISATION_LOST, message)
