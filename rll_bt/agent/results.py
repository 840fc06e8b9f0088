"""A task's result as the league says it, and as rll-bt adds to it.

The league's robots answer a task by sending it back (``AgentTask``) with
``successful``, ``canceled`` and, on failure, ``error_code``; the agent does
the same, with the code in the league's words (:mod:`rll_bt.agenttask.codes`).
For an rll-bt team server a ``TaskOutcome`` goes just before it, with
rll-bt's own code, the text and whether the gripper holds a workpiece.
"""
from __future__ import annotations

from .. import msgs
from ..agenttask import codes
from .taskbook import Result

STATUSES = ("SUCCEEDED", "FAILED", "CANCELLED")


def echo(task, robot_id: int, team_color: int | None = None):
    """A copy of AgentTask ``task`` to answer it with: the same task, this
    robot's number, no cancel / pause request and no result yet."""
    lm = msgs.message_set("rcll2025")
    at = lm.AgentTask()
    at.CopyFrom(task)
    at.robot_id = int(robot_id)
    if team_color is not None:
        at.team_color = int(team_color)
    for f in ("cancel_task", "pause_task", "successful", "canceled", "error_code"):
        at.ClearField(f)
    return at


def make_result(task, *, robot_id: int, status: str, code: str = "NONE", text: str = "",
                holding: bool | None = None, stamp: float = 0.0, league_code: str | None = None,
                team_color: int | None = None) -> Result:
    """The result of AgentTask ``task``: ``status`` SUCCEEDED / FAILED /
    CANCELLED, ``code`` rll-bt's ErrorCode name (FAILED), ``league_code`` the
    league's code when the task was refused before it ran (else derived
    from ``code``), ``holding`` the gripper afterwards (None: unknown)."""
    if status not in STATUSES:
        raise ValueError(f"status must be one of {', '.join(STATUSES)}, not {status!r}")
    tm = msgs.message_set("team")
    at = echo(task, robot_id, team_color)
    at.successful = status == "SUCCEEDED"
    at.canceled = status == "CANCELLED"
    if status == "FAILED":
        at.error_code = codes.league_value(league_code or codes.to_league(code, text, holding))
    elif status == "CANCELLED":
        code = "CANCELLED"
    out = tm.TaskOutcome(task_id=int(task.task_id), robot_id=int(robot_id),
                         error=tm.enum("ErrorCode").Value(code if code in codes.TO_LEAGUE else "INTERNAL"),
                         stamp=float(stamp))
    if text:
        out.text = text[:500]
    if holding is not None:
        out.holding = bool(holding)
    return Result(at, out)


#: the task kinds that take a workpiece into the gripper (a league robot refuses them with one held)
TAKES = ("get_workpiece", "retrieve_cap")


def full_gripper_refusal(entry, holding: bool | None, *, robot_id: int, stamp: float) -> Result | None:
    """The refusal of a league team server's retrieve or buffer (``entry`` without rll-bt's detail)
    while the gripper holds a workpiece: the trees would count the held workpiece as the one to take
    (as after a pause of rll-bt's own task), so it fails as the league's robots do; None otherwise."""
    if entry.detail is not None or entry.kind not in TAKES or not holding:
        return None
    return make_result(entry.task, robot_id=robot_id, status="FAILED", code="INVALID_TASK",
                       text="the gripper already holds a workpiece",
                       league_code="WORKPIECE_ALREADY_IN_GRIPPER", holding=True, stamp=stamp)


def follow_refusal(entry, holding: bool | None, *, robot_id: int, stamp: float) -> Result:
    """The refusal of a task rll-bt's team server sent to run after another (its
    TaskDetail's ``after``) that did not succeed (or that this robot never ran):
    FAILED with NOT_RUNNING, which the server answers by giving the task out anew."""
    return make_result(entry.task, robot_id=robot_id, status="FAILED", code="NOT_RUNNING",
                       text=f"the task before it ({entry.after}) did not succeed", holding=holding, stamp=stamp)
