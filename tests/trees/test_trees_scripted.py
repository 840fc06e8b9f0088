"""The real task trees on the scripted backend, with scripted doubles of the
skill nodes: every task kind succeeds, and the recovery branches fire in
their order on injected failures (an empty gripper after a grab, drive
faults, a lost pose), ending with the error code the team server gets."""
from __future__ import annotations

import pytest

from backends.scripted import ScriptedBackend
from rll_bt.clock import SimClock
from rll_bt.comm import Bus
from tests.support import TREES
from tests.support.agents import KEY, LM, TEAM_REG, Rig, ScriptedServer
from tests.support.tree_doubles import CALLS, REGISTRY, Hands, calls


def make(holding=False, misses=0, stuck=0, **script):
    CALLS.clear()
    clock = SimClock()
    bus = Bus(clock)
    backend = ScriptedBackend(dict(script), clock=clock)
    srv = ScriptedServer(bus.stream_server("ts", registry=TEAM_REG, key=KEY))
    rig = Rig(bus.stream_client("ts", registry=TEAM_REG, key=KEY), srv, clock, backend=backend,
              registry=REGISTRY, trees_dir=TREES)
    rig.hands = Hands(backend, holding, misses, stuck)
    rig.extra.append(rig.hands)
    rig.until(lambda: rig.agent.gate.moving_allowed, what="game running")
    return rig


def run(rig, kind, seconds=120.0, **fields):
    rig.server.next = getattr(rig.server, "next", 0) + 1
    tid = rig.server.next
    rig.server.task(tid, kind, **fields)
    rig.until(lambda: rig.server.final(tid) is not None, seconds=seconds, what=f"{kind} finished")
    return rig.server.final(tid)


def outcome(res) -> tuple[str, str]:
    return res.status, res.code


def skills_called() -> list[str]:
    return [k for k, _v in CALLS if k != "localised"]


@pytest.mark.parametrize("kind, fields, holding, after", [
    ("explore_zone", {"zone": 6}, False, False),
    ("get_workpiece", {"machine": "C-BS"}, False, True),
    ("get_workpiece", {"machine": "C-CS1", "side": "SHELF", "shelf_slot": 2}, False, True),
    ("put_workpiece", {"machine": "C-RS1", "side": "SLIDE"}, True, False),
    ("retrieve_cap", {"machine": "C-CS2", "shelf_slot": 1}, False, False),
    ("mount_ring", {"machine": "C-RS2", "ring_color": "RING_BLUE"}, True, False),
    ("mount_cap", {"machine": "C-CS1"}, True, False),
    ("deliver", {"machine": "C-DS", "gate": 1}, True, False),
    ("discard", {}, True, False),
    ("discard", {"machine": "C-RS1", "side": "SLIDE"}, True, False),
    ("go_to", {"zone": 7}, False, False),
    ("go_to", {"x": 1.5, "y": 3.0, "theta": 0.5}, True, True),
])
def test_every_task_kind_succeeds(kind, fields, holding, after):
    rig = make(holding=holding)
    res = run(rig, kind, **fields)
    assert outcome(res) == ("SUCCEEDED", "NONE"), res.text
    assert rig.backend.holding() is after and bool(res.holding) is after
    assert rig.drives()[-1][1] == "stop"


def test_retrieve_cap_takes_from_the_shelf_and_feeds_the_input():
    rig = make()
    run(rig, "retrieve_cap", machine="C-CS2", shelf_slot=1)
    places = [(v["side"], v.get("shelf_slot")) for k, v in CALLS if k in ("grab", "put")]
    assert places == [("SHELF", 1), ("INPUT", 0)]


def test_an_empty_gripper_after_the_grab_re_aligns_and_retries():
    rig = make(misses=1)
    res = run(rig, "get_workpiece", machine="C-BS")
    assert outcome(res) == ("SUCCEEDED", "NONE")
    assert skills_called() == ["approach_station", "grab", "back_off", "approach_station", "grab"]
    assert calls("back_off")[0][1]["distance"] == 0.2
    assert rig.hands.closes == 2


def test_a_grab_that_never_holds_escalates_and_reports_grab_failed():
    rig = make(misses=99)
    res = run(rig, "get_workpiece", machine="C-BS")
    assert outcome(res) == ("FAILED", "GRAB_FAILED")
    assert skills_called() == ["approach_station", "grab",
                               "back_off", "approach_station", "grab",                 # re-align and retry
                               "back_off", "relocalise", "approach_station", "grab"]   # back off, re-localise
    assert [v["distance"] for _k, v in calls("back_off")] == [0.2, 0.5]
    assert not res.holding and rig.drives()[-1][1] == "stop"


def test_a_navigation_failure_backs_off_and_replans():
    rig = make(faults=[{"method": "drive", "call": 1, "message": "wheel slip"}])
    res = run(rig, "get_workpiece", machine="C-BS")
    assert outcome(res) == ("SUCCEEDED", "NONE")
    assert skills_called() == ["approach_station", "back_off", "approach_station", "grab"]
    assert calls("back_off")[0][1]["distance"] == 0.4


def test_an_approach_that_lost_the_pose_relocalises_instead_of_backing_off():
    rig = make(faults=[{"method": "drive", "call": 1, "message": "pose lost"}])
    res = run(rig, "get_workpiece", machine="C-BS")
    assert outcome(res) == ("SUCCEEDED", "NONE")
    assert skills_called() == ["approach_station", "relocalise", "approach_station", "grab"]


def test_a_go_to_that_lost_the_pose_relocalises_instead_of_backing_off():
    rig = make(faults=[{"method": "drive", "call": 1, "message": "pose lost"}])
    res = run(rig, "go_to", zone=7)
    assert outcome(res) == ("SUCCEEDED", "NONE")
    assert skills_called() == ["navigate_to_zone", "relocalise", "navigate_to_zone"]


def test_navigation_that_never_works_ends_in_navigation_failed():
    rig = make(holding=True, faults=[{"method": "drive", "after": 0.0, "message": "motor fault"}])
    res = run(rig, "put_workpiece", machine="C-RS1")
    assert outcome(res) == ("FAILED", "NAVIGATION_FAILED")
    assert skills_called() == ["approach_station", "back_off", "approach_station",
                               "relocalise", "relocalise", "approach_station"]
    assert "motor fault" in res.text
    assert rig.drives()[-1][1] == "stop"


def test_a_lost_pose_is_recovered_before_the_task():
    rig = make(readings={"confidence": [{"t": 0.0, "value": 0.05}]})
    res = run(rig, "get_workpiece", machine="C-BS")
    assert outcome(res) == ("SUCCEEDED", "NONE")
    assert [k for k, _v in CALLS][:3] == ["localised", "relocalise", "approach_station"]


def test_a_put_that_does_not_let_go_reports_put_failed():
    rig = make(holding=True, stuck=99)
    res = run(rig, "mount_cap", machine="C-CS1")
    assert outcome(res) == ("FAILED", "PUT_FAILED")
    assert skills_called().count("put") == 3 and res.holding


def test_a_lost_workpiece_is_reported_before_driving():
    rig = make(holding=False)
    res = run(rig, "deliver", machine="C-DS", gate=1)
    assert outcome(res) == ("FAILED", "PUT_FAILED") and "lost" in res.text
    assert skills_called() == []


@pytest.mark.parametrize("kind, machine", [("deliver", "C-RS1"), ("mount_ring", "C-CS1"), ("mount_cap", "C-BS"),
                                           ("retrieve_cap", "C-RS2")])
def test_the_wrong_kind_of_station_is_an_invalid_task(kind, machine):
    rig = make(holding=True)
    fields = {"machine": machine}
    if kind == "retrieve_cap":
        fields["shelf_slot"] = 0
    if kind == "mount_ring":
        fields["ring_color"] = "RING_BLUE"
    res = run(rig, kind, **fields)
    assert outcome(res) == ("FAILED", "INVALID_TASK") and skills_called() == []


def test_a_pause_after_the_grab_does_not_grab_again():
    rig = make()
    rig.server.task(1, "get_workpiece", machine="C-BS")
    rig.until(lambda: rig.hands.closes == 1, what="gripper closed")
    rig.run(1.5)                                          # the grab is done, the task not yet reported
    rig.server.send_phase("PAUSED")
    rig.run(1.0)
    assert rig.drives()[-1][1] == "stop"
    rig.server.send_phase("RUNNING")
    rig.until(lambda: rig.server.results(1, "SUCCEEDED"), what="done after the pause")
    assert skills_called().count("grab") == 1


def test_go_to_drives_to_the_pose_it_was_given():
    rig = make()
    res = run(rig, "go_to", x=-2.5, y=4.0, theta=1.0, zone=3)
    assert outcome(res) == ("SUCCEEDED", "NONE")
    assert skills_called() == ["navigate_to_pose"]
    goal = calls("navigate_to_pose")[0][1]["goal"]
    assert (goal.x, goal.y, goal.theta) == (-2.5, 4.0, 1.0)


def test_go_to_a_zone_uses_the_zone_navigation():
    rig = make()
    res = run(rig, "go_to", zone=7)
    assert outcome(res) == ("SUCCEEDED", "NONE")
    assert skills_called() == ["navigate_to_zone"] and calls("navigate_to_zone")[0][1]["zone"] == 7


def test_go_to_that_never_arrives_backs_off_relocalises_and_fails():
    rig = make(faults=[{"method": "drive", "after": 0.0, "message": "motor fault"}])
    res = run(rig, "go_to", zone=7)
    assert outcome(res) == ("FAILED", "NAVIGATION_FAILED")
    assert skills_called() == ["navigate_to_zone", "back_off", "navigate_to_zone",
                               "relocalise", "relocalise", "navigate_to_zone"]


def test_a_move_to_nowhere_is_refused():
    rig = make()
    nowhere = LM.AgentTask(team_color=0, task_id=99, robot_id=1)
    nowhere.move.waypoint = "Z99"
    rig.server.send_agent_task(nowhere)
    rig.until(lambda: rig.server.final(99) is not None, what="refused")
    res = rig.server.final(99)
    assert outcome(res) == ("FAILED", "INVALID_TASK") and skills_called() == []
    assert LM.AgentTask.ErrorCode.Name(res.league_code) == "INVALID_TARGET"


def test_a_discard_without_a_station_never_drives():
    rig = make(holding=True)
    res = run(rig, "discard")
    assert outcome(res) == ("SUCCEEDED", "NONE") and not res.holding
    assert skills_called() == []
    assert all(d[1] == "stop" for d in rig.drives()), rig.drives()


def _machine_info(**states):
    from types import SimpleNamespace
    return SimpleNamespace(machines=[SimpleNamespace(name=n.replace("_", "-"), state=s)
                                     for n, s in states.items()])


@pytest.mark.parametrize("kind, fields, machine", [
    ("mount_ring", {"machine": "C-RS2", "ring_color": "RING_BLUE"}, "C-RS2"),
    ("mount_cap", {"machine": "C-CS1"}, "C-CS1"),
    ("retrieve_cap", {"machine": "C-CS2", "shelf_slot": 1}, "C-CS2"),
    ("put_workpiece", {"machine": "C-CS1", "side": "INPUT"}, "C-CS1"),
])
def test_a_feed_waits_docked_until_the_refbox_shows_the_station_prepared(kind, fields, machine):
    """Never a workpiece on a station that is not PREPARED for it: the robot docks, then
    puts only once MachineInfo shows the station PREPARED.  While it waits its RobotStatus
    says where (``waiting_at``: a 2025 team server prepares the station only then), and
    no more once it has put."""
    rig = make(holding=kind != "retrieve_cap")
    rig.agent.stations.update(_machine_info(**{machine.replace("-", "_"): "IDLE"}), rig.clock.now())
    rig.server.next = getattr(rig.server, "next", 0) + 1
    tid = rig.server.next
    rig.server.task(tid, kind, **fields)
    rig.until(lambda: calls("approach_station") and rig.clock.now() > 30, seconds=60, what="waiting docked")
    assert not [v for k, v in CALLS if k == "put"]              # docked, not fed
    rig.until(lambda: rig.server.of("RobotStatus")[-1].waiting_at == machine, seconds=5,
              what="waiting_at in the RobotStatus")
    rig.agent.stations.update(_machine_info(**{machine.replace("-", "_"): "PREPARED"}), rig.clock.now())
    rig.until(lambda: rig.server.final(tid) is not None, seconds=60, what="fed")
    assert outcome(rig.server.final(tid)) == ("SUCCEEDED", "NONE") and [v for k, v in CALLS if k == "put"]
    rig.until(lambda: not rig.server.of("RobotStatus")[-1].HasField("waiting_at"), seconds=5,
              what="no waiting_at once fed")


def test_a_delivery_takes_a_ds_waiting_for_its_window_or_delivering():
    rig = make(holding=True)
    rig.agent.stations.update(_machine_info(C_DS="PROCESSING"), rig.clock.now())
    assert outcome(run(rig, "deliver", machine="C-DS", order_id=3)) == ("SUCCEEDED", "NONE")


@pytest.mark.parametrize("state, code", [("IDLE", "TIMEOUT"), ("BROKEN", "MACHINE_BROKEN")])
def test_a_station_never_prepared_ends_the_feed_without_putting(state, code):
    rig = make(holding=True)
    rig.agent.stations.update(_machine_info(C_RS1=state), rig.clock.now())
    res = run(rig, "mount_ring", seconds=300, machine="C-RS1", ring_color="RING_BLUE")
    assert outcome(res)[1] == code and not [v for k, v in CALLS if k == "put"]
    assert rig.backend.holding()
