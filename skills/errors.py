"""Failure codes of the skills.

The names match the team protocol's task ``ErrorCode`` (the mid-level
reports them to the team server unchanged): ``NAVIGATION_FAILED``,
``LOCALISATION_LOST``, ``ALIGN_FAILED``, ``GRAB_FAILED``, ``PUT_FAILED``,
``TIMEOUT``, ...  A failed activity carries one code and a message that
says what was seen.
"""
from __future__ import annotations

import enum


class SkillError(enum.Enum):
    NONE = "NONE"
    CANCELLED = "CANCELLED"              # stopped by the caller, not a fault
    TIMEOUT = "TIMEOUT"                  # did not finish within its time limit
    NAVIGATION_FAILED = "NAVIGATION_FAILED"   # no path, or blocked for too long
    LOCALISATION_LOST = "LOCALISATION_LOST"   # pose confidence fell below the limit
    ALIGN_FAILED = "ALIGN_FAILED"        # the station's tag was not seen or not reached
    GRAB_FAILED = "GRAB_FAILED"          # the gripper does not hold a workpiece after a grab
    PUT_FAILED = "PUT_FAILED"            # the gripper still holds the workpiece after a put
    MACHINE_UNKNOWN = "MACHINE_UNKNOWN"  # the station's pose is not known yet
    BAD_GOAL = "BAD_GOAL"                # the goal is outside the field or inside an obstacle
    HARDWARE = "HARDWARE"                # the backend reported an error (gripper, base)


class SkillFailure(Exception):
    """Raised inside an activity step to end it with ``code``."""

    def __init__(self, code: SkillError, message: str):
        super().__init__(f"{code.value}: {message}")
        self.code = code
        self.message = message
