"""The team server's side: an rll-bt task as the league's AgentTask (+ TaskDetail).

rll-bt's team server plans in task kinds of its own (:data:`KINDS`, the
names of the trees in ``trees/``) with a dict of parameters; on the wire
each becomes an ``llsf_msgs.AgentTask`` that a peer knowing only the
league's messages understands, and an ``rllbt.TaskDetail`` with what the
AgentTask cannot say, for robots that run rll-bt's agent:

===============  ============================================  ==========================
kind             AgentTask                                     TaskDetail adds
===============  ============================================  ==========================
explore_zone     explore_machine {machine_id: the station      viewpoints
                 looked for or "", machine_point "",
                 waypoint: the zone}
go_to            move {waypoint: the zone, else the zone of     target (the pose), zone
                 the pose}
get_workpiece    retrieve {machine_id, machine_point           shelf_slot (SHELF)
                 output / input / shelf}
put_workpiece    deliver {machine_id, machine_point            --
                 input / slide}
retrieve_cap     buffer {machine_id, shelf_number: slot + 1}   --
mount_ring       deliver {machine_id, "input"}                 ring_color
mount_cap        deliver {machine_id, "input"}                 cap_color
deliver          deliver {machine_id, "input"}, order_id       gate (rcll2016)
discard          deliver {machine_id, input / slide}, or       --
                 without a station move {waypoint: the
                 robot's zone}
===============  ============================================  ==========================

TaskDetail always names the kind, so an rll-bt robot runs exactly the tree
the server meant (a ``deliver`` to a ring station's input is a mount_ring,
a discard there is not).  ``workpiece_description`` and ``order_id`` are
set when the caller knows them (the refbox's task tracking reads them from
the robots' beacons).  A discard without a station has no form a robot
that knows only the league's tasks would execute: the team server gives
such robots a station to discard at instead (see ``docs/league.md``).
"""
from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

from .. import msgs
from ..rules import Profile

KINDS = ("explore_zone", "go_to", "get_workpiece", "put_workpiece", "retrieve_cap", "mount_ring",
         "mount_cap", "deliver", "discard")
TEAM_VALUE = {"CYAN": 0, "MAGENTA": 1}
LOOK = "look"          # explore_zone parameter: the station the exploration looks for


def _point(side: str | None, default: str) -> str:
    return str(side or default).lower()


def nearest_zone(profile: Profile, x: float, y: float) -> int:
    """The zone containing (x, y), else the one whose centre is nearest."""
    z = profile.zone_at(x, y)
    if z is not None:
        return z
    return min(profile.zones.all_zones,
               key=lambda n: math.hypot(profile.zone_centre(n)[0] - x, profile.zone_centre(n)[1] - y))


def render_task(kind: str, params: dict[str, Any], *, task_id: int, robot_id: int, color: str | None,
                profile: Profile, workpiece: tuple[str, Sequence[str], str | None] | None = None,
                order_id: int | None = None, robot_zone: int | None = None,
                issued_at: float | None = None):
    """``(AgentTask, TaskDetail)`` for the rll-bt task ``kind`` with ``params``.

    ``color``: our team colour ("CYAN"/"MAGENTA"; None counts as cyan);
    ``workpiece``: (base, rings, cap) colour names of the workpiece the task
    handles, for ``workpiece_description``; ``order_id``: the order it serves;
    ``robot_zone``: where the robot stands (a discard without a station).
    ValueError for a kind with no AgentTask form."""
    lm, tm = msgs.message_set("rcll2025"), msgs.message_set("team")
    at = lm.AgentTask(team_color=TEAM_VALUE.get(color or "CYAN", 0), task_id=int(task_id),
                      robot_id=int(robot_id))
    detail = tm.TaskDetail(task_id=int(task_id), robot_id=int(robot_id), kind=kind)
    if issued_at is not None:
        detail.issued_at = float(issued_at)
    if params.get("timeout"):
        detail.timeout = float(params["timeout"])
    p = params
    machine = p.get("machine") or ""
    if kind == "explore_zone":
        zone = int(p["zone"])
        at.explore_machine.machine_id = str(p.get(LOOK) or "")
        at.explore_machine.machine_point = ""
        at.explore_machine.waypoint = profile.zone_name(zone)
        for x, y, theta in p.get("viewpoints", ()):
            detail.viewpoints.add(x=float(x), y=float(y), theta=float(theta))
    elif kind == "go_to":
        if "x" not in p and not p.get("zone"):
            raise ValueError("a go_to needs a pose (x, y) or a zone")
        if "x" in p:
            x, y = float(p["x"]), float(p["y"])
            zone = int(p["zone"]) if p.get("zone") else nearest_zone(profile, x, y)
            detail.target.x, detail.target.y, detail.target.theta = x, y, float(p.get("theta", 0.0))
        else:
            zone = int(p["zone"])
        at.move.waypoint = profile.zone_name(zone)
        if p.get("zone"):
            detail.zone = int(p["zone"])
    elif kind == "get_workpiece":
        side = p.get("side", "OUTPUT")
        at.retrieve.machine_id = machine
        at.retrieve.machine_point = _point(side, "output")
        if side == "SHELF":
            detail.shelf_slot = int(p.get("shelf_slot", 0))
    elif kind == "put_workpiece":
        at.deliver.machine_id = machine
        at.deliver.machine_point = _point(p.get("side"), "input")
    elif kind == "retrieve_cap":
        at.buffer.machine_id = machine
        at.buffer.shelf_number = int(p.get("shelf_slot", 0)) + 1
    elif kind in ("mount_ring", "mount_cap", "deliver"):
        at.deliver.machine_id = machine
        at.deliver.machine_point = "input"
        if kind == "mount_ring":
            detail.ring_color = tm.enum("RingColor").Value(p["ring_color"])
        elif kind == "mount_cap" and p.get("cap_color"):
            detail.cap_color = tm.enum("CapColor").Value(p["cap_color"])
        elif kind == "deliver":
            if "gate" in p:
                detail.gate = int(p["gate"])
            if p.get("order_id"):
                order_id = int(p["order_id"])
    elif kind == "discard":
        if machine:
            at.deliver.machine_id = machine
            at.deliver.machine_point = _point(p.get("side"), "input")
        else:
            at.move.waypoint = profile.zone_name(robot_zone) if robot_zone else ""
    else:
        raise ValueError(f"no AgentTask for an rll-bt task of kind {kind!r}")
    if order_id:
        at.order_id = int(order_id)
    if workpiece is not None and workpiece[0]:
        base, rings, cap = workpiece
        pc = lm.enum("BaseColor"), lm.enum("RingColor"), lm.enum("CapColor")
        wd = at.workpiece_description
        wd.base_color = pc[0].Value(base)
        wd.ring_colors.extend(pc[1].Value(r) for r in rings)
        if cap:
            wd.cap_color = pc[2].Value(cap)
    return at, detail


def render_cancel(task_id: int, robot_id: int, color: str | None):
    """The AgentTask that cancels task ``task_id`` of robot ``robot_id``."""
    lm = msgs.message_set("rcll2025")
    return lm.AgentTask(team_color=TEAM_VALUE.get(color or "CYAN", 0), task_id=int(task_id),
                        robot_id=int(robot_id), cancel_task=True)


def render_pause(task_id: int, robot_id: int, color: str | None, pause: bool = True):
    """The AgentTask that pauses (``pause``) or resumes task ``task_id``."""
    lm = msgs.message_set("rcll2025")
    return lm.AgentTask(team_color=TEAM_VALUE.get(color or "CYAN", 0), task_id=int(task_id),
                        robot_id=int(robot_id), pause_task=bool(pause))
