"""The team protocol (package rllbt, what rll-bt adds to the league's AgentTask):
what the team server and the robots rely on."""
from __future__ import annotations

import pytest

from rll_bt import msgs

TEAM = msgs.message_set("team")


def test_package_and_comp_id():
    assert TEAM.package == "rllbt"
    assert {ct[0] for ct in TEAM.by_comp_type} == {3000}
    for name in ("TaskDetail", "TaskOutcome", "MachineObservation", "ZoneExplored",
                 "RobotHello", "Heartbeat", "RobotStatus", "MachineMap", "GamePhase"):
        assert TEAM.comp_type(TEAM.get(name)) is not None, name
    for gone in ("Task", "TaskResult", "CancelTask"):        # the league's AgentTask does their work
        assert gone not in TEAM


def test_task_detail_and_outcome_ride_beside_an_agent_task():
    d = TEAM.TaskDetail(task_id=7, robot_id=2, kind="go_to", zone=0, timeout=30.0)
    d.target.x, d.target.y, d.target.theta = 1.0, 2.0, 0.5
    d.viewpoints.add(x=1.0, y=1.0, theta=0.0)
    assert d.IsInitialized() and TEAM.TaskDetail.FromString(d.SerializeToString()) == d
    o = TEAM.TaskOutcome(task_id=7, robot_id=2, error=TEAM.enum("ErrorCode").Value("GRAB_FAILED"),
                         text="gripper empty after grab", holding=False)
    assert msgs.to_dict(o)["error"] == "GRAB_FAILED"
    assert TEAM.TaskOutcome(task_id=1, robot_id=1).error == TEAM.enum("ErrorCode").Value("NONE")


def test_error_codes():
    codes = TEAM.enum("ErrorCode")
    for name in ("NONE", "NAVIGATION_FAILED", "LOCALISATION_LOST", "MACHINE_NOT_FOUND",
                 "ALIGN_FAILED", "GRAB_FAILED", "PUT_FAILED", "GRIPPER_ERROR", "TIMEOUT",
                 "CANCELLED", "MACHINE_BROKEN", "NOT_RUNNING", "INVALID_TASK", "INTERNAL"):
        assert name in codes.keys()
    assert codes.Value("NONE") == 0
    assert len(set(codes.values())) == len(codes.keys())


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
