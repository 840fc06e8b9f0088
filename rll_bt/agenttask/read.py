"""The robot's side: an AgentTask (+ TaskDetail) as an rll-bt tree and its parameters.

:func:`read_task` turns the league's task into the task kind whose tree the
agent runs (``trees/<kind>.yaml``) and the ``$task.NAME`` parameters.  With
an rll-bt team server's ``TaskDetail`` the kind and every parameter are
exactly those the server meant (see :mod:`.render`); from a team server
that speaks only the league's messages the kind follows from the task:

=================================  ==========================================
AgentTask                          tree
=================================  ==========================================
move {zone}                        go_to (to the free spot of the zone nearest
                                   its centre)
move {machine, input/output}       go_to (in front of that side of the station)
retrieve {machine, input/output}   get_workpiece
retrieve {CS, shelf}               get_workpiece from whichever shelf slot
                                   holds a workpiece (shelf_slot -1)
deliver {machine, input}           deliver at a DS, mount_ring at an RS,
                                   mount_cap at a CS, put_workpiece elsewhere
deliver {RS, slide}                put_workpiece on the slide
buffer {CS, shelf_number 1..3}     retrieve_cap from slot shelf_number - 1
explore_machine {machine, _, zone}  explore_zone: the zone the robot knows the
                                   station in, else the waypoint zone
=================================  ==========================================

A task that cannot be run raises :class:`TaskRejected` with the league's
code: WRONG_TEAM, WRONG_ROBOT, INVALID_TARGET (no such zone or station, a
station that has no such point, another team's station) or
TASK_NOT_SUPPORTED (no task in it, or a TaskDetail that does not fit it).

Every kind's parameters: ``task_id``, ``robot_id``, ``team_color``
("CYAN"/"MAGENTA"), ``kind``, ``timeout`` (s, 0 = none); per kind:

===============  ==================================================================
explore_zone     zone (int), zone_name, viewpoints (list of [x, y, theta])
get_workpiece    machine, machine_type, side (INPUT/OUTPUT/SHELF), shelf_slot (-1: any),
                 face (INPUT/OUTPUT), place (conveyor/shelf0..2/shelf)
put_workpiece    machine, machine_type, side (INPUT/SLIDE), face, place (conveyor/slide)
retrieve_cap     machine, machine_type, shelf_slot, face (INPUT), place (shelfN)
mount_ring       machine, machine_type, ring_color ("RING_BLUE" ... or ""), face, place
mount_cap        machine, machine_type, cap_color ("CAP_BLACK"/"CAP_GREY"/""), face, place
deliver          machine, machine_type, gate (0: none), order_id (0: none), face, place
discard          machine ("": where the robot stands), machine_type, side, face, place
go_to            zone (0: none), zone_name, has_target, target ({x, y, theta}; the
                 zone's centre without one), machine and side (a station to go to)
===============  ==================================================================
"""
from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from .. import msgs
from ..rules import Profile, machine_team, machine_type

#: the kinds each AgentTask body may carry (the first one when a TaskDetail names none)
BODY_KINDS = {
    "move": ("go_to", "discard"),
    "retrieve": ("get_workpiece",),
    "deliver": ("put_workpiece", "mount_ring", "mount_cap", "deliver", "discard"),
    "buffer": ("retrieve_cap",),
    "explore_machine": ("explore_zone",),
}
BODIES = tuple(BODY_KINDS)
COLORS = ("CYAN", "MAGENTA")
#: shelf_slot of a retrieve from a shelf that names no slot: whichever slot holds a workpiece
ANY_SLOT = -1
#: the kind a deliver to a station's input runs, by station type
DELIVER_KIND = {"DS": "deliver", "RS": "mount_ring", "CS": "mount_cap"}


class TaskRejected(ValueError):
    """A task the robot will not run: ``code`` is the league's ErrorCode name."""

    def __init__(self, code: str, text: str):
        super().__init__(f"{code}: {text}")
        self.code = code
        self.text = text


def body_of(at) -> str | None:
    """Which of the task fields (move, retrieve, deliver, buffer, explore_machine) is set."""
    for name in BODIES:
        if at.HasField(name):
            return name
    return None


def _zone(profile: Profile, name: str) -> int:
    try:
        return profile.zone_number(str(name).strip())
    except ValueError:
        raise TaskRejected("INVALID_TARGET", f"{name!r} is not a zone of {profile.name}") from None


def _machine(profile: Profile, name: str, color: str | None) -> str:
    name = str(name).strip()
    if name not in profile.tags:
        raise TaskRejected("INVALID_TARGET", f"{profile.name} has no station {name!r}")
    if color is not None and machine_team(name) != color:
        raise TaskRejected("INVALID_TARGET", f"{name} is a station of the other team")
    return name


def _place(side: str, slot: int = 0) -> tuple[str, str]:
    """(face, place) of a station side as the navigation skills name them
    (``shelf`` for :data:`ANY_SLOT`)."""
    if side == "SHELF":
        return "INPUT", f"shelf{slot}" if slot >= 0 else "shelf"
    if side == "SLIDE":
        return "INPUT", "slide"
    return side, "conveyor"


def _point(value: str, allowed: tuple[str, ...], what: str) -> str:
    side = str(value).strip().upper()
    if side not in allowed:
        raise TaskRejected("INVALID_TARGET", f"{what} at machine point {value!r} (valid: "
                           + ", ".join(a.lower() for a in allowed) + ")")
    return side


def _kind(body: str, detail, machine: str | None, point: str | None) -> str:
    kinds = BODY_KINDS[body]
    if detail is not None and detail.HasField("kind") and detail.kind:
        if detail.kind not in kinds:
            raise TaskRejected("TASK_NOT_SUPPORTED", f"a {body} task cannot be a {detail.kind}")
        return detail.kind
    if body == "deliver" and point == "INPUT" and machine:
        return DELIVER_KIND.get(machine_type(machine), "put_workpiece")
    return kinds[0]


def read_task(at, detail=None, *, profile: Profile, robot_id: int, color: str | None = None,
              machines: Mapping[str, Any] | None = None) -> tuple[str, dict[str, Any]]:
    """``(kind, params)`` of AgentTask ``at`` for robot ``robot_id`` of team
    ``color`` (None: not checked).  ``detail``: the TaskDetail of the same task
    (or None); ``machines``: what the robot knows of the stations (name ->
    anything with ``zone``), used by explore_machine without a TaskDetail.
    :class:`TaskRejected` when the robot cannot run it."""
    team = COLORS[at.team_color] if at.team_color in (0, 1) else None
    if color is not None and team != color:
        raise TaskRejected("WRONG_TEAM", f"task {at.task_id} is for team {team or at.team_color}, "
                           f"this robot plays {color}")
    if int(at.robot_id) != int(robot_id):
        raise TaskRejected("WRONG_ROBOT", f"task {at.task_id} is for robot {at.robot_id}, this is robot {robot_id}")
    if detail is not None and (detail.task_id != at.task_id or detail.robot_id != at.robot_id):
        detail = None
    body = body_of(at)
    if body is None:
        raise TaskRejected("TASK_NOT_SUPPORTED", f"task {at.task_id} names no task (move, retrieve, "
                           "deliver, buffer, explore_machine)")
    p: dict[str, Any] = {"task_id": int(at.task_id), "robot_id": int(at.robot_id),
                         "team_color": team or "CYAN",
                         "timeout": float(detail.timeout) if detail is not None and detail.HasField("timeout") else 0.0}
    b = getattr(at, body)
    if body == "move":
        kind = _kind(body, detail, None, None)
        p["kind"] = kind
        return kind, (_discard(p, "", "INPUT") if kind == "discard" else _move(p, b, detail, profile, color))
    if body == "explore_machine":
        p["kind"] = "explore_zone"
        return "explore_zone", _explore(p, b, detail, profile, machines)
    machine = _machine(profile, b.machine_id, color)
    mtype = machine_type(machine)
    p["machine"], p["machine_type"] = machine, mtype
    if body == "buffer":
        kind = _kind(body, detail, machine, None)
        if mtype != "CS":
            raise TaskRejected("INVALID_TARGET", f"{machine} has no shelf to buffer a cap from")
        if not 1 <= int(b.shelf_number) <= 3:
            raise TaskRejected("INVALID_TARGET", f"shelf number {b.shelf_number} is not 1..3")
        slot = int(b.shelf_number) - 1
        p.update(kind=kind, shelf_slot=slot)
        p["face"], p["place"] = _place("SHELF", slot)
        return kind, p
    if body == "retrieve":
        side = _point(b.machine_point, ("INPUT", "OUTPUT", "SHELF"), "nothing can be retrieved")
        if side == "SHELF" and mtype != "CS":
            raise TaskRejected("INVALID_TARGET", f"{machine} has no shelf")
        kind = _kind(body, detail, machine, side)
        named = detail is not None and detail.HasField("shelf_slot")
        slot = int(detail.shelf_slot) if named else (ANY_SLOT if side == "SHELF" else 0)
        if side == "SHELF" and named and not 0 <= slot <= 2:
            raise TaskRejected("INVALID_TARGET", f"shelf slot {slot} is not 0..2")
        p.update(kind=kind, side=side, shelf_slot=slot)
        p["face"], p["place"] = _place(side, slot)
        return kind, p
    side = _point(b.machine_point, ("INPUT", "SLIDE"), "nothing can be delivered")
    if side == "SLIDE" and mtype != "RS":
        raise TaskRejected("INVALID_TARGET", f"{machine} has no slide")
    kind = _kind(body, detail, machine, side)
    p["kind"] = kind
    if kind == "discard":
        return kind, _discard(p, machine, side)
    if kind == "put_workpiece":
        p["side"] = side
    elif side == "SLIDE":
        raise TaskRejected("TASK_NOT_SUPPORTED", f"a {kind} does not go on a slide")
    tm = msgs.message_set("team")
    if kind == "mount_ring":
        has = detail is not None and detail.HasField("ring_color")
        p["ring_color"] = tm.enum("RingColor").Name(detail.ring_color) if has else ""
    elif kind == "mount_cap":
        has = detail is not None and detail.HasField("cap_color")
        p["cap_color"] = tm.enum("CapColor").Name(detail.cap_color) if has else ""
    elif kind == "deliver":
        p["gate"] = int(detail.gate) if detail is not None and detail.HasField("gate") else 0
        p["order_id"] = int(at.order_id) if at.HasField("order_id") else 0
    p["face"], p["place"] = _place(side)
    return kind, p


def _discard(p: dict[str, Any], machine: str, side: str) -> dict[str, Any]:
    p["machine"] = machine
    p["machine_type"] = machine_type(machine) if machine else ""
    p["side"] = side
    p["face"], p["place"] = _place(side)
    return p


def _move(p: dict[str, Any], b, detail, profile: Profile, color: str | None) -> dict[str, Any]:
    has_target = detail is not None and detail.HasField("target")
    machine, side = "", "INPUT"
    if has_target:
        zone = int(detail.zone) if detail.HasField("zone") else 0
        if zone and zone not in profile.zones.all_zones:
            raise TaskRejected("INVALID_TARGET", f"zone {zone} does not exist in {profile.name}")
        t = detail.target
        target = {"x": float(t.x), "y": float(t.y), "theta": float(t.theta)}
    elif str(b.waypoint).strip() in profile.tags:
        machine = _machine(profile, b.waypoint, color)
        side = _point(b.machine_point or "input", ("INPUT", "OUTPUT"), "a robot cannot go")
        zone, target = 0, {"x": 0.0, "y": 0.0, "theta": 0.0}
    else:
        zone = _zone(profile, b.waypoint)
        cx, cy = profile.zone_centre(zone)
        target = {"x": float(cx), "y": float(cy), "theta": 0.0}
    p.update(zone=zone, zone_name=profile.zone_name(zone) if zone else "", has_target=has_target,
             target=target, machine=machine, side=side)
    return p


def _explore(p: dict[str, Any], b, detail, profile: Profile, machines) -> dict[str, Any]:
    zone = None
    if detail is None and b.machine_id and machines is not None:
        known = machines.get(str(b.machine_id).strip())
        z = getattr(known, "zone", None)
        if z and z in profile.zones.all_zones:
            zone = int(z)
    if zone is None:
        zone = _zone(profile, b.waypoint)
    viewpoints = [[v.x, v.y, v.theta] for v in detail.viewpoints] if detail is not None else []
    p.update(zone=zone, zone_name=profile.zone_name(zone), viewpoints=viewpoints)
    return p
