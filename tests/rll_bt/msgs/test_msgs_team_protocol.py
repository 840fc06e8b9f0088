"""The team protocol (package rllbt): what the team server and the robots rely on."""
from __future__ import annotations

import pytest

from rll_bt import msgs

TEAM = msgs.message_set("team")


def test_package_and_comp_id():
    assert TEAM.package == "rllbt"
    assert {ct[0] for ct in TEAM.by_comp_type} == {3000}
    for name in ("Task", "TaskResult", "CancelTask", "MachineObservation", "ZoneExplored",
                 "RobotHello", "Heartbeat", "RobotStatus", "MachineMap", "GamePhase"):
        assert TEAM.comp_type(TEAM.get(name)) is not None, name


def test_task_holds_exactly_one_kind():
    t = TEAM.Task(team_color=0, task_id=1, robot_id=1)
    assert t.WhichOneof("kind") is None
    t.explore_zone.zone = 1054
    assert t.WhichOneof("kind") == "explore_zone"
    t.mount_ring.machine = "C-RS1"
    t.mount_ring.ring_color = TEAM.enum("RingColor").Value("RING_GREEN")
    assert t.WhichOneof("kind") == "mount_ring"
    assert not t.HasField("explore_zone")
    kinds = {f.name for f in TEAM.Task.DESCRIPTOR.oneofs_by_name["kind"].fields}
    assert kinds == {"explore_zone", "get_workpiece", "put_workpiece", "retrieve_cap",
                     "mount_ring", "mount_cap", "deliver", "discard", "report_machines", "go_to"}


def test_deliver_by_gate_or_order():
    d = TEAM.Deliver(machine="C-DS", gate=2)
    assert d.WhichOneof("target") == "gate"
    d.order_id = 7
    assert d.WhichOneof("target") == "order_id" and not d.HasField("gate")


def test_side_defaults():
    side = TEAM.enum("MachineSide")
    assert TEAM.GetWorkpiece(machine="C-BS").side == side.Value("OUTPUT")
    assert TEAM.PutWorkpiece(machine="C-CS1").side == side.Value("INPUT")
    assert set(side.keys()) == {"INPUT", "OUTPUT", "SHELF", "SLIDE"}


def test_task_result_status_and_error_codes():
    status = TEAM.enum("TaskResult.Status")
    assert {k: status.Value(k) for k in status.keys()} == {
        "RUNNING": 1, "SUCCEEDED": 2, "FAILED": 3, "CANCELLED": 4}
    codes = TEAM.enum("ErrorCode")
    for name in ("NONE", "NAVIGATION_FAILED", "LOCALISATION_LOST", "MACHINE_NOT_FOUND",
                 "ALIGN_FAILED", "GRAB_FAILED", "PUT_FAILED", "GRIPPER_ERROR", "TIMEOUT",
                 "CANCELLED", "MACHINE_BROKEN", "NOT_RUNNING", "INVALID_TASK", "INTERNAL"):
        assert name in codes.keys()
    assert codes.Value("NONE") == 0
    assert len(set(codes.values())) == len(codes.keys())
    r = TEAM.TaskResult(task_id=3, robot_id=1, status=status.Value("FAILED"),
                        error=codes.Value("GRAB_FAILED"), text="gripper empty after grab")
    assert msgs.to_dict(r)["error"] == "GRAB_FAILED"
    assert TEAM.TaskResult(task_id=1, robot_id=1, status=2).error == codes.Value("NONE")


def test_machine_observation_per_property_confidence():
    obs = msgs.from_dict(TEAM, "MachineObservation", {
        "robot_id": 2,
        "name": {"value": "M-CS2", "confidence": 0.9},
        "tag_id": {"value": 203, "confidence": 1.0},
        "pose": {"pose": {"x": -3.5, "y": 4.5, "theta": 1.57},
                 "covariance": [0.01, 0, 0, 0, 0.01, 0, 0, 0, 0.05], "confidence": 0.8},
        "zone": {"value": 1045, "confidence": 0.8},
        "orientation": {"value": 90, "confidence": 0.6},
        "lights": {"pattern": 5, "red": "ON", "yellow": "OFF", "green": "ON",
                   "confidence": 0.7},
        "stamp": 12.5,
    }, require_initialized=True)
    assert obs.lights.pattern == 5 and obs.pose.covariance[8] == pytest.approx(0.05)
    assert TEAM.MachineObservation.FromString(obs.SerializeToString()) == obs
    # a search that found nothing in a zone
    none = TEAM.MachineObservation(robot_id=2, searched_zone=7, seen_in_zone=False)
    assert none.IsInitialized() and not none.HasField("name")


def test_machine_map_and_game_phase():
    mm = TEAM.MachineMap(profile="rcll2025")
    mm.machines.add(name="C-BS", type="BS", team_color=0, zone=11, rotation=90,
                    input_tag=122, output_tag=121, confidence=1.0)
    assert TEAM.MachineMap.FromString(mm.SerializeToString()) == mm
    gp = TEAM.GamePhase(state=TEAM.GamePhase.RUNNING, phase=TEAM.GamePhase.PRODUCTION,
                        game_time=42.0)
    assert gp.IsInitialized()
    # the same numbers as the refbox's GameState
    r16 = msgs.message_set("rcll2016")
    for enum in ("State", "Phase"):
        ours, theirs = TEAM.enum(f"GamePhase.{enum}"), r16.enum(f"GameState.{enum}")
        assert {k: ours.Value(k) for k in ours.keys()} == {k: theirs.Value(k) for k in theirs.keys()}


def test_hello_heartbeat_status():
    hello = TEAM.RobotHello(robot_id=1, team_name="GRIPS", peer_name="R1", restarted=True)
    hello.capabilities.extend(["explore", "grip"])
    assert hello.IsInitialized()
    assert TEAM.Heartbeat(robot_id=1, seq=2 ** 40).IsInitialized()
    st = TEAM.RobotStatus(robot_id=1, state=TEAM.RobotStatus.BUSY, current_task_id=5,
                          battery_voltage=23.8, battery_fraction=0.8)
    st.holding.base = TEAM.enum("BaseColor").Value("BASE_RED")
    st.holding.rings.append(TEAM.enum("RingColor").Value("RING_BLUE"))
    assert msgs.to_dict(st)["holding"] == {"base": "BASE_RED", "rings": ["RING_BLUE"]}


def test_colour_values_match_the_refbox():
    r25 = msgs.message_set("rcll2025")
    for ours, theirs in (("TeamColor", "Team"), ("BaseColor", "BaseColor"),
                         ("RingColor", "RingColor"), ("CapColor", "CapColor"),
                         ("LightState", "LightState")):
        a, b = TEAM.enum(ours), r25.enum(theirs)
        assert sorted(a.values()) == sorted(b.values()), ours
