"""Error codes: rll-bt's ``rllbt.ErrorCode`` and the league's ``AgentTask.ErrorCode``.

The skills and trees name failures in rll-bt's words (``GRAB_FAILED``,
``NAVIGATION_FAILED``, ...; ``rll_bt/msgs/proto/team/common.proto``); on the
wire a result carries the league's code in ``AgentTask.error_code``
(``reference/league-interfaces.md``), so a team server that knows only the
league's messages understands it.  rll-bt's own code still travels to an
rll-bt team server in ``TaskOutcome.error``.

==========================  =====================================================
rll-bt                      league (AgentTask.ErrorCode)
==========================  =====================================================
NONE                        NO_ERROR
NAVIGATION_FAILED           UNABLE_TO_MOVE_TO_TARGET (NO_PATH_FOUND when the
                            navigation said it found no path)
LOCALISATION_LOST           UNABLE_TO_MOVE_TO_TARGET
MACHINE_NOT_FOUND           MPS_NOT_FOUND
ALIGN_FAILED                NOT_AT_POSITION
GRAB_FAILED                 GRASPING_FAILED (NO_WORKPIECE_FOUND when the robot
                            found nothing to take: "no workpiece found ...")
PUT_FAILED                  MACHINE_POINT_OCCUPIED while the gripper still holds
                            the workpiece, NO_WORKPIECE_IN_GRIPPER once it is empty
GRIPPER_ERROR, SENSOR_LOST  INTERNAL_ERROR
TIMEOUT, MACHINE_BROKEN,
NOT_RUNNING                 UNKNOWN
INVALID_TASK                INVALID_TARGET (the task reader says WRONG_TEAM,
                            WRONG_ROBOT, INVALID_TARGET or TASK_NOT_SUPPORTED
                            itself)
INTERNAL                    INTERNAL_ERROR
CANCELLED                   (none: ``canceled`` is set instead)
==========================  =====================================================

Back from a robot that sends no ``TaskOutcome`` (any robot that knows only
the league's messages), :func:`from_league` names the league's code in
rll-bt's words so the team server's recoveries apply: a failure without a
code (or ``UNKNOWN``) is ``NONE``, which the team server simply tries again.
"""
from __future__ import annotations

from functools import cache

from .. import msgs

#: rll-bt ErrorCode name -> league ErrorCode name (PUT_FAILED: see :func:`to_league`)
TO_LEAGUE = {
    "NONE": "NO_ERROR",
    "NAVIGATION_FAILED": "UNABLE_TO_MOVE_TO_TARGET",
    "LOCALISATION_LOST": "UNABLE_TO_MOVE_TO_TARGET",
    "MACHINE_NOT_FOUND": "MPS_NOT_FOUND",
    "ALIGN_FAILED": "NOT_AT_POSITION",
    "GRAB_FAILED": "GRASPING_FAILED",
    "PUT_FAILED": "MACHINE_POINT_OCCUPIED",
    "GRIPPER_ERROR": "INTERNAL_ERROR",
    "TIMEOUT": "UNKNOWN",
    "CANCELLED": "NO_ERROR",
    "MACHINE_BROKEN": "UNKNOWN",
    "NOT_RUNNING": "UNKNOWN",
    "INVALID_TASK": "INVALID_TARGET",
    "INTERNAL": "INTERNAL_ERROR",
    "SENSOR_LOST": "INTERNAL_ERROR",
}

#: how a GRAB_FAILED's text begins when there was nothing to take (skills/manipulation/shelf.py)
NOTHING_FOUND = "no workpiece found"

#: league ErrorCode name -> rll-bt ErrorCode name
FROM_LEAGUE = {
    "NO_ERROR": "NONE",
    "UNKNOWN": "NONE",
    "WRONG_TEAM": "INVALID_TASK",
    "WRONG_ROBOT": "INVALID_TASK",
    "INVALID_TARGET": "INVALID_TASK",
    "TASK_NOT_SUPPORTED": "INVALID_TASK",
    "NOT_AT_POSITION": "ALIGN_FAILED",
    "UNABLE_TO_MOVE_TO_TARGET": "NAVIGATION_FAILED",
    "NO_WORKPIECE_FOUND": "GRAB_FAILED",
    "MPS_NOT_FOUND": "MACHINE_NOT_FOUND",
    "WORKPIECE_SENSOR_DISAGREEMENT": "GRIPPER_ERROR",
    "ABORTED_DUE_TO_UNEXPECTED_COLLISION": "NAVIGATION_FAILED",
    "GRASPING_FAILED": "GRAB_FAILED",
    "WORKPIECE_ALREADY_IN_GRIPPER": "INVALID_TASK",
    "NO_WORKPIECE_IN_GRIPPER": "PUT_FAILED",
    "MACHINE_POINT_OCCUPIED": "PUT_FAILED",
    "INTERNAL_ERROR": "INTERNAL",
    "NO_PATH_FOUND": "NAVIGATION_FAILED",
}

#: league codes that tell whether the gripper holds a workpiece after the failure
HOLDING_AFTER = {"WORKPIECE_ALREADY_IN_GRIPPER": True, "MACHINE_POINT_OCCUPIED": True,
                 "NO_WORKPIECE_IN_GRIPPER": False}


@cache
def league_codes():
    """The league's ErrorCode enum (``AgentTask.ErrorCode`` of the rcll2025 set)."""
    return msgs.message_set("rcll2025").enum("AgentTask.ErrorCode")


@cache
def rllbt_codes():
    """rll-bt's ErrorCode enum (``rllbt.ErrorCode`` of the team set)."""
    return msgs.message_set("team").enum("ErrorCode")


def league_value(name: str) -> int:
    """The number of the league's code ``name`` (ValueError for another name)."""
    return league_codes().Value(name)


def league_name(value: int) -> str | None:
    """The name of the league's code ``value``; None for a number the league does not define."""
    try:
        return league_codes().Name(int(value))
    except ValueError:
        return None


def to_league(code: str, text: str = "", holding: bool | None = None) -> str:
    """The league's code name for rll-bt's ``code`` (an unknown name counts as
    INTERNAL).  ``holding`` (the gripper afterwards) and ``text`` refine
    PUT_FAILED, NAVIGATION_FAILED and GRAB_FAILED."""
    code = code if code in TO_LEAGUE else "INTERNAL"
    if code == "PUT_FAILED" and holding is False:
        return "NO_WORKPIECE_IN_GRIPPER"
    if code == "NAVIGATION_FAILED" and "no path" in text.lower():
        return "NO_PATH_FOUND"
    if code == "GRAB_FAILED" and NOTHING_FOUND in text.lower():
        return "NO_WORKPIECE_FOUND"
    return TO_LEAGUE[code]


def from_league(value: int | None) -> str:
    """rll-bt's ErrorCode name for the league's code ``value`` (None or unset:
    NONE; a number the league does not define: INTERNAL)."""
    if value is None:
        return "NONE"
    name = league_name(value)
    return FROM_LEAGUE.get(name, "INTERNAL") if name is not None else "INTERNAL"


def holding_after(value: int | None) -> bool | None:
    """Whether a result with the league's code ``value`` says the gripper
    holds a workpiece (None: it does not say)."""
    name = league_name(value) if value is not None else None
    return HOLDING_AFTER.get(name) if name is not None else None
