"""Team-protocol tasks as tree parameters.

Each ``rllbt.Task`` carries one ``kind`` (its oneof); the agent runs the
tree ``<kind>.yaml`` of its trees directory with the parameters below as
``$task.NAME``.  Every task gives ``task_id``, ``robot_id``,
``team_color`` ("CYAN"/"MAGENTA"), ``kind`` and ``timeout`` (seconds,
0 = none); per kind:

===============  ==================================================================
kind             parameters
===============  ==================================================================
explore_zone     zone (int, profile zone number), zone_name (str, e.g. "Z12"),
                 viewpoints (list of [x, y, theta], field frame, may be empty)
get_workpiece    machine, machine_type ("BS" ...), side (INPUT/OUTPUT/SHELF),
                 shelf_slot (int), face (INPUT/OUTPUT), place (conveyor/shelf0..2)
put_workpiece    machine, machine_type, side (INPUT/SLIDE), face, place (conveyor/slide)
retrieve_cap     machine, machine_type, shelf_slot, face (INPUT), place (shelfN)
mount_ring       machine, machine_type, ring_color ("RING_BLUE" ...), face, place
mount_cap        machine, machine_type, cap_color ("CAP_BLACK"/"CAP_GREY"/""), face, place
deliver          machine, machine_type, gate (int, 0: none), order_id (int, 0: none),
                 face, place
discard          machine ("" : anywhere safe), machine_type, side, face, place
go_to            zone (int, 0: none), zone_name (str, "" : none), has_target (bool),
                 target ({x, y, theta}, field frame; the zone's centre when only a
                 zone is given)
report_machines  entries (list of {name, type, zone, rotation}); run by the agent
                 itself (a MachineReport to the refbox), no tree
===============  ==================================================================

``face`` is the station face the robot works at (the shelf and the slide
are on the input face) and ``place`` the spot on it, as the navigation
skills name them.  The 2025 storage station needs no kind of its own: the
team server stores a product with put_workpiece to its INPUT and retrieves
it with get_workpiece from its OUTPUT (it sends the STORE / RETRIEVE
PrepareMachine itself).
"""
from __future__ import annotations

from typing import Any

from .. import msgs
from ..rules import Profile, machine_type

TASK_KINDS = ("explore_zone", "get_workpiece", "put_workpiece", "retrieve_cap", "mount_ring", "mount_cap",
              "deliver", "discard", "go_to", "report_machines")
#: kinds that run a tree (report_machines is done by the agent itself)
TREE_KINDS = TASK_KINDS[:-1]
#: what the agent reads from a task tree that succeeded: kind -> {output name: type}; the
#: tree declares these under ``outputs:`` (explore_zone: the stations seen, for ZoneExplored)
TREE_OUTPUTS: dict[str, dict[str, str]] = {"explore_zone": {"found": "list"}}


def output_problems(kind: str, spec) -> list[str]:
    """What the tree ``spec`` of ``kind`` lacks of the outputs the agent reads."""
    out = []
    for name, tname in TREE_OUTPUTS.get(kind, {}).items():
        decl = spec.outputs.get(name)
        if decl is None:
            out.append(f"{kind}.yaml declares no output {name!r} ({tname}), which the agent reads")
        elif decl.ptype.name != tname:
            out.append(f"{kind}.yaml declares output {name!r} as {decl.ptype.name}; the agent reads a {tname}")
    return out


class InvalidTask(ValueError):
    """A task the agent cannot run as given (reported as INVALID_TASK)."""


def task_kind(task) -> str:
    kind = task.WhichOneof("kind")
    if kind is None:
        raise InvalidTask(f"task {task.task_id} has no kind")
    return kind


def _enum_name(enum_name: str, value: int) -> str:
    return msgs.message_set("team").enum(enum_name).Name(value)


def _station(machine: str) -> str:
    try:
        return machine_type(machine)
    except ValueError as exc:
        raise InvalidTask(str(exc)) from None


def _place(side: str, slot: int = 0) -> tuple[str, str]:
    """(face, place) of a protocol MachineSide."""
    if side == "SHELF":
        if not 0 <= slot <= 2:
            raise InvalidTask(f"shelf slot {slot} is not 0..2")
        return "INPUT", f"shelf{slot}"
    if side == "SLIDE":
        return "INPUT", "slide"
    return side, "conveyor"


def task_params(task, profile: Profile) -> dict[str, Any]:
    """The ``$task.NAME`` values of ``task`` (see the module docstring).
    Raises :class:`InvalidTask` for a task no tree can run."""
    kind = task_kind(task)
    body = getattr(task, kind)
    p: dict[str, Any] = {
        "task_id": int(task.task_id), "robot_id": int(task.robot_id),
        "team_color": _enum_name("TeamColor", task.team_color), "kind": kind,
        "timeout": float(task.timeout) if task.HasField("timeout") else 0.0,
    }
    if kind == "explore_zone":
        zone = int(body.zone)
        if zone not in profile.zones.all_zones:
            raise InvalidTask(f"zone {zone} does not exist in {profile.name}")
        p.update(zone=zone, zone_name=profile.zone_name(zone),
                 viewpoints=[[v.x, v.y, v.theta] for v in body.viewpoints])
        return p
    if kind == "go_to":
        return _go_to_params(p, body, profile)
    if kind == "report_machines":
        p["entries"] = [{"name": e.name, "type": e.type, "zone": int(e.zone), "rotation": int(e.rotation)}
                        for e in body.entries]
        return p
    machine = body.machine if (kind != "discard" or body.HasField("machine")) else ""
    if machine and machine not in profile.tags:
        raise InvalidTask(f"{profile.name} has no machine {machine!r}")
    p["machine"] = machine
    p["machine_type"] = _station(machine) if machine else ""
    if kind == "get_workpiece":
        side = _enum_name("MachineSide", body.side)
        if side == "SLIDE":
            raise InvalidTask("nothing can be taken from a slide")
        slot = int(body.shelf_slot)
        p.update(side=side, shelf_slot=slot)
        p["face"], p["place"] = _place(side, slot)
    elif kind in ("put_workpiece", "discard"):
        side = _enum_name("MachineSide", body.side)
        if side in ("OUTPUT", "SHELF"):
            raise InvalidTask(f"cannot put a workpiece on a station's {side.lower()}")
        p["side"] = side
        p["face"], p["place"] = _place(side)
    elif kind == "retrieve_cap":
        slot = int(body.shelf_slot)
        p["shelf_slot"] = slot
        p["face"], p["place"] = _place("SHELF", slot)
    elif kind == "mount_ring":
        p["ring_color"] = _enum_name("RingColor", body.ring_color)
        p["face"], p["place"] = "INPUT", "conveyor"
    elif kind == "mount_cap":
        p["cap_color"] = _enum_name("CapColor", body.cap_color) if body.HasField("cap_color") else ""
        p["face"], p["place"] = "INPUT", "conveyor"
    elif kind == "deliver":
        target = body.WhichOneof("target")
        p["gate"] = int(body.gate) if target == "gate" else 0
        p["order_id"] = int(body.order_id) if target == "order_id" else 0
        p["face"], p["place"] = "INPUT", "conveyor"
    return p


def _go_to_params(p: dict[str, Any], body, profile: Profile) -> dict[str, Any]:
    zone = int(body.zone) if body.HasField("zone") else 0
    if zone and zone not in profile.zones.all_zones:
        raise InvalidTask(f"zone {zone} does not exist in {profile.name}")
    if not zone and not body.HasField("target"):
        raise InvalidTask("a go_to task needs a zone or a target pose")
    if body.HasField("target"):
        t = body.target
        target = {"x": float(t.x), "y": float(t.y), "theta": float(t.theta)}
    else:
        cx, cy = profile.zone_centre(zone)
        target = {"x": float(cx), "y": float(cy), "theta": 0.0}
    p.update(zone=zone, zone_name=profile.zone_name(zone) if zone else "",
             has_target=body.HasField("target"), target=target)
    return p


# -- the refbox's view of a task (rcll2025 BeaconSignal.task) ---------------------------

def _agent_point(side: str) -> str:
    return {"OUTPUT": "output", "INPUT": "input", "SHELF": "shelf", "SLIDE": "slide"}.get(side, "input")


def agent_task(ms, task, params: dict[str, Any], profile: Profile, color: str):
    """The rcll2025 ``AgentTask`` describing ``task`` for the refbox (in
    BeaconSignal.task), or None when it has no AgentTask form."""
    if "AgentTask" not in ms.classes:
        return None
    at = ms.AgentTask(team_color=ms.enum("Team").Value(color), task_id=int(task.task_id),
                      robot_id=int(task.robot_id))
    kind = params["kind"]
    machine = params.get("machine", "")
    if kind == "go_to" and params["zone"] or kind == "explore_zone":
        at.move.waypoint = profile.zone_name(params["zone"])
    elif kind == "get_workpiece":
        at.retrieve.machine_id = machine
        at.retrieve.machine_point = _agent_point(params["side"])
    elif kind == "retrieve_cap":
        at.buffer.machine_id = machine
        at.buffer.shelf_number = params["shelf_slot"] + 1
    elif kind in ("put_workpiece", "mount_ring", "mount_cap", "deliver", "discard") and machine:
        at.deliver.machine_id = machine
        at.deliver.machine_point = _agent_point(params.get("side", "INPUT"))
        if kind == "deliver" and params.get("order_id"):
            at.order_id = params["order_id"]
    else:
        return None
    return at
