"""rll-bt tasks as the league's AgentTask and back (rll_bt.agenttask.render / .read)."""
from __future__ import annotations

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from rll_bt import msgs, rules
from rll_bt.agenttask import TaskRejected, read_task, render_cancel, render_pause, render_task

P16, P25 = rules.profile("rcll2016"), rules.profile("rcll2025")
LM, TM = msgs.message_set("rcll2025"), msgs.message_set("team")


def roundtrip(kind, params, profile=P16, color="CYAN", **kw):
    at, detail = render_task(kind, params, task_id=7, robot_id=2, color=color, profile=profile, **kw)
    # over the wire: both messages survive serialisation unchanged
    at2, d2 = LM.AgentTask.FromString(at.SerializeToString()), TM.TaskDetail.FromString(detail.SerializeToString())
    return at2, d2, read_task(at2, d2, profile=profile, robot_id=2, color=color)


def test_every_kind_comes_back_as_the_tree_and_parameters_the_server_meant():
    common = {"task_id": 7, "robot_id": 2, "team_color": "CYAN", "timeout": 0.0}
    expect = [
        ("explore_zone", {"zone": 5, "viewpoints": [[1.0, 2.0, 0.5]], "look": "C-CS1"},
            {"zone": 5, "zone_name": "Z5", "viewpoints": [[1.0, 2.0, 0.5]]}),
        ("go_to", {"x": 1.5, "y": 2.5, "theta": 0.25},
            {"zone": 0, "zone_name": "", "has_target": True, "target": {"x": 1.5, "y": 2.5, "theta": 0.25},
             "machine": "", "side": "INPUT"}),
        ("get_workpiece", {"machine": "C-BS", "side": "OUTPUT"},
            {"machine": "C-BS", "machine_type": "BS", "side": "OUTPUT", "shelf_slot": 0, "face": "OUTPUT",
             "place": "conveyor"}),
        ("put_workpiece", {"machine": "C-RS1", "side": "SLIDE"},
            {"machine": "C-RS1", "machine_type": "RS", "side": "SLIDE", "face": "INPUT", "place": "slide"}),
        ("retrieve_cap", {"machine": "C-CS2", "shelf_slot": 2},
            {"machine": "C-CS2", "machine_type": "CS", "shelf_slot": 2, "face": "INPUT", "place": "shelf2"}),
        ("mount_ring", {"machine": "C-RS2", "ring_color": "RING_ORANGE"},
            {"machine": "C-RS2", "machine_type": "RS", "ring_color": "RING_ORANGE", "face": "INPUT",
             "place": "conveyor"}),
        ("mount_cap", {"machine": "C-CS1", "cap_color": "CAP_GREY"},
            {"machine": "C-CS1", "machine_type": "CS", "cap_color": "CAP_GREY", "face": "INPUT", "place": "conveyor"}),
        ("deliver", {"machine": "C-DS", "gate": 2},
            {"machine": "C-DS", "machine_type": "DS", "gate": 2, "order_id": 0, "face": "INPUT", "place": "conveyor"}),
        ("discard", {},
            {"machine": "", "machine_type": "", "side": "INPUT", "face": "INPUT", "place": "conveyor"}),
    ]
    for kind, params, want in expect:
        _at, _d, (got_kind, got) = roundtrip(kind, params, robot_zone=3)
        assert got_kind == kind
        assert got == {**common, "kind": kind, **want}, kind


def test_the_agent_task_says_it_in_the_leagues_words():
    at, d, _ = roundtrip("explore_zone", {"zone": 5, "look": "C-CS1"})
    assert (at.explore_machine.machine_id, at.explore_machine.waypoint) == ("C-CS1", "Z5")
    at, d, _ = roundtrip("go_to", {"x": 1.5, "y": 2.5})       # the zone the pose lies in
    assert at.move.waypoint == P16.zone_name(P16.zone_at(1.5, 2.5))
    at, _, _ = roundtrip("get_workpiece", {"machine": "C-BS", "side": "OUTPUT"})
    assert (at.retrieve.machine_id, at.retrieve.machine_point) == ("C-BS", "output")
    at, _, _ = roundtrip("retrieve_cap", {"machine": "C-CS1", "shelf_slot": 0})
    assert (at.buffer.machine_id, at.buffer.shelf_number) == ("C-CS1", 1)
    at, _, _ = roundtrip("put_workpiece", {"machine": "C-RS1", "side": "SLIDE"})
    assert (at.deliver.machine_id, at.deliver.machine_point) == ("C-RS1", "slide")
    at, _, _ = roundtrip("deliver", {"machine": "C-DS", "order_id": 4}, profile=P25,
                         workpiece=("BASE_RED", ["RING_BLUE"], "CAP_BLACK"))
    assert (at.deliver.machine_id, at.deliver.machine_point, at.order_id) == ("C-DS", "input", 4)
    wd = at.workpiece_description
    assert (wd.base_color, list(wd.ring_colors), wd.cap_color) == (1, [1], 1)
    at, _, _ = roundtrip("discard", {}, robot_zone=7)
    assert at.move.waypoint == "Z7"
    with pytest.raises(ValueError, match="report_machines"):
        render_task("report_machines", {}, task_id=1, robot_id=1, color="CYAN", profile=P16)


def league(body: str, task_id=3, robot=2, color=0, **fields):
    at = LM.AgentTask(team_color=color, task_id=task_id, robot_id=robot)
    b = getattr(at, body)
    b.SetInParent()
    for k, v in fields.items():
        setattr(b, k, v)
    return at


@pytest.mark.parametrize("body,fields,kind,extra", [
    ("move", {"waypoint": "C_Z33"}, "go_to", {"zone": 33, "has_target": False}),
    ("move", {"waypoint": "C-BS", "machine_point": "output"}, "go_to", {"machine": "C-BS", "side": "OUTPUT"}),
    ("retrieve", {"machine_id": "C-BS", "machine_point": "output"}, "get_workpiece", {"side": "OUTPUT"}),
    ("retrieve", {"machine_id": "C-CS1", "machine_point": "shelf"}, "get_workpiece",
     {"side": "SHELF", "shelf_slot": -1, "place": "shelf"}),          # no slot named: any that holds one
    ("deliver", {"machine_id": "C-DS", "machine_point": "input"}, "deliver", {"gate": 0}),
    ("deliver", {"machine_id": "C-RS1", "machine_point": "input"}, "mount_ring", {"ring_color": ""}),
    ("deliver", {"machine_id": "C-CS2", "machine_point": "input"}, "mount_cap", {"cap_color": ""}),
    ("deliver", {"machine_id": "C-SS", "machine_point": "input"}, "put_workpiece", {"side": "INPUT"}),
    ("deliver", {"machine_id": "C-RS2", "machine_point": "slide"}, "put_workpiece", {"side": "SLIDE"}),
    ("buffer", {"machine_id": "C-CS1", "shelf_number": 3}, "retrieve_cap", {"shelf_slot": 2}),
    ("explore_machine", {"machine_id": "C-RS1", "machine_point": "input", "waypoint": "C_Z52"}, "explore_zone",
     {"zone": 52, "viewpoints": []}),
])
def test_a_league_team_servers_tasks_run_the_matching_tree(body, fields, kind, extra):
    got_kind, p = read_task(league(body, **fields), None, profile=P25, robot_id=2, color="CYAN")
    assert got_kind == kind and p["kind"] == kind
    assert {k: p[k] for k in extra} == extra


def test_explore_goes_to_the_zone_the_robot_knows_the_station_in():
    class Known:
        zone = 41
    at = league("explore_machine", machine_id="C-RS1", machine_point="input", waypoint="C_Z52")
    _, p = read_task(at, None, profile=P25, robot_id=2, machines={"C-RS1": Known()})
    assert p["zone"] == 41
    _, p = read_task(at, None, profile=P25, robot_id=2, machines={})
    assert p["zone"] == 52


@pytest.mark.parametrize("at,code", [
    (league("move", color=1, waypoint="C_Z33"), "WRONG_TEAM"),
    (league("move", robot=3, waypoint="C_Z33"), "WRONG_ROBOT"),
    (league("move", waypoint="C_Z99"), "INVALID_TARGET"),
    (league("move", waypoint="somewhere"), "INVALID_TARGET"),
    (league("move", waypoint="C-BS", machine_point="shelf"), "INVALID_TARGET"),
    (league("retrieve", machine_id="C-XX", machine_point="output"), "INVALID_TARGET"),
    (league("retrieve", machine_id="M-BS", machine_point="output"), "INVALID_TARGET"),
    (league("retrieve", machine_id="C-BS", machine_point="shelf"), "INVALID_TARGET"),
    (league("retrieve", machine_id="C-BS", machine_point="slide"), "INVALID_TARGET"),
    (league("deliver", machine_id="C-DS", machine_point="output"), "INVALID_TARGET"),
    (league("deliver", machine_id="C-CS1", machine_point="slide"), "INVALID_TARGET"),
    (league("buffer", machine_id="C-RS1", shelf_number=1), "INVALID_TARGET"),
    (league("buffer", machine_id="C-CS1", shelf_number=0), "INVALID_TARGET"),
    (league("buffer", machine_id="C-CS1", shelf_number=4), "INVALID_TARGET"),
    (LM.AgentTask(team_color=0, task_id=3, robot_id=2), "TASK_NOT_SUPPORTED"),
])
def test_a_task_that_cannot_be_done_is_rejected_with_the_leagues_code(at, code):
    with pytest.raises(TaskRejected) as err:
        read_task(at, None, profile=P25, robot_id=2, color="CYAN")
    assert err.value.code == code and err.value.text


def test_a_detail_that_does_not_fit_its_task_is_not_followed():
    at = league("retrieve", machine_id="C-BS", machine_point="output")
    with pytest.raises(TaskRejected) as err:
        read_task(at, TM.TaskDetail(task_id=3, robot_id=2, kind="mount_cap"), profile=P25, robot_id=2)
    assert err.value.code == "TASK_NOT_SUPPORTED"
    # a detail of another task is ignored
    kind, _ = read_task(at, TM.TaskDetail(task_id=4, robot_id=2, kind="mount_cap"), profile=P25, robot_id=2)
    assert kind == "get_workpiece"


def test_cancel_and_pause_are_agent_tasks_with_their_flag():
    c = render_cancel(5, 2, "MAGENTA")
    assert (c.task_id, c.robot_id, c.team_color, c.cancel_task) == (5, 2, 1, True)
    p = render_pause(5, 2, "CYAN", pause=False)
    assert p.HasField("pause_task") and p.pause_task is False


@settings(max_examples=300, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.binary(max_size=200), st.binary(max_size=60))
def test_any_bytes_are_read_or_rejected_never_a_crash(task_bytes, detail_bytes):
    at, detail = LM.AgentTask(), TM.TaskDetail()
    try:
        at.MergeFromString(task_bytes)
        detail.MergeFromString(detail_bytes)
    except Exception:
        return
    for profile in (P16, P25):
        try:
            kind, params = read_task(at, detail, profile=profile, robot_id=at.robot_id, color=None)
        except TaskRejected as exc:
            assert exc.code in ("WRONG_TEAM", "WRONG_ROBOT", "INVALID_TARGET", "TASK_NOT_SUPPORTED")
        else:
            assert params["kind"] == kind
