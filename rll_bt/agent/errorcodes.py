"""Tree error codes to the team protocol's ``ErrorCode``.

Trees leave a code on the blackboard (``fail_with_error``, ``recovery``,
``timeout``); the skills name theirs after the protocol (``GRAB_FAILED``,
``NAVIGATION_FAILED``, ...), so most codes pass unchanged.  A few other
spellings are accepted; anything unknown becomes ``INTERNAL`` and the
original code goes into the result's text.
"""
from __future__ import annotations

from .. import msgs

#: other spellings -> ErrorCode names
ALIASES = {
    "GRASP_FAILED": "GRAB_FAILED",
    "GRAB": "GRAB_FAILED",
    "PUT": "PUT_FAILED",
    "NAV_FAILED": "NAVIGATION_FAILED",
    "NO_PATH": "NAVIGATION_FAILED",
    "BAD_GOAL": "NAVIGATION_FAILED",
    "LOCALIZATION_LOST": "LOCALISATION_LOST",
    "LOST": "LOCALISATION_LOST",
    "MACHINE_UNKNOWN": "MACHINE_NOT_FOUND",
    "TAG_NOT_FOUND": "MACHINE_NOT_FOUND",
    "ALIGN": "ALIGN_FAILED",
    "HARDWARE": "INTERNAL",
    "GRIPPER": "GRIPPER_ERROR",
    "MACHINE_DOWN": "MACHINE_BROKEN",
    "BROKEN": "MACHINE_BROKEN",
    "INVALID": "INVALID_TASK",
    "ERROR": "INTERNAL",
}


def error_code(code: str | None) -> tuple[int, str]:
    """(ErrorCode value, name) for a tree's error code; unknown -> INTERNAL."""
    enum = msgs.message_set("team").enum("ErrorCode")
    if not code:
        return enum.Value("INTERNAL"), "INTERNAL"
    name = str(code).strip().upper().replace("-", "_").replace(" ", "_")
    name = ALIASES.get(name, name)
    if name in enum.keys():
        return enum.Value(name), name
    return enum.Value("INTERNAL"), "INTERNAL"
