"""How the agent runs tasks (lockstep, over the in-process bus): outcomes and
their error codes, timeouts, bugs in nodes, refused tasks, re-sent tasks,
observations, results kept while the link is down."""
from __future__ import annotations

import pytest

from rll_bt.clock import SimClock
from rll_bt.comm import Bus
from tests.support.agents import KEY, TEAM_REG, TM, Rig, ScriptedServer

STATE = TM.RobotStatus.State
SIDE = TM.MachineSide.Value


@pytest.fixture
def rig():
    clock = SimClock()
    bus = Bus(clock)
    srv = ScriptedServer(bus.stream_server("ts", registry=TEAM_REG, key=KEY))
    r = Rig(bus.stream_client("ts", registry=TEAM_REG, key=KEY), srv, clock)
    r.bus = bus
    r.until(lambda: r.agent.gate.moving_allowed, what="game running")
    return r


def final(srv, tid):
    out = [r for r in srv.results(tid) if TM.TaskResult.Status.Name(r.status) != "RUNNING"]
    return out[-1] if out else None


def run_task(rig, tid, kind, seconds=20.0, **fields):
    rig.server.task(tid, kind, **fields)
    rig.until(lambda: final(rig.server, tid) is not None, seconds=seconds, what=f"task {tid} {kind} finished")
    return final(rig.server, tid)


def code(result) -> str:
    return TM.ErrorCode.Name(result.error)


def test_recovery_runs_and_its_error_code_is_reported(rig):
    res = run_task(rig, 1, "put_workpiece", machine="C-RS1")
    assert TM.TaskResult.Status.Name(res.status) == "FAILED" and code(res) == "PUT_FAILED"
    assert res.text == "the workpiece is still in the gripper"
    seen = [STATE.Name(s.state) for s in rig.server.of("RobotStatus")]
    assert "RECOVERING" in seen and seen[-1] == "IDLE"


def test_task_timeout_counts_running_time(rig):
    res = run_task(rig, 2, "deliver", machine="C-DS", gate=1, timeout=2.0)
    assert code(res) == "TIMEOUT" and "2 s" in res.text
    assert res.stamp == pytest.approx(rig.server.results(2, "RUNNING")[0].stamp + 2.0, abs=0.25)


def test_a_node_that_raises_fails_the_task_not_the_agent(rig):
    res = run_task(rig, 3, "mount_ring", machine="C-RS1", ring_color=1)
    assert code(res) == "INTERNAL" and "node bug" in res.text
    assert rig.drives()[-1][1] == "stop"
    assert run_task(rig, 4, "get_workpiece", machine="C-BS").status == TM.TaskResult.SUCCEEDED


def test_a_tree_failing_without_a_code_reports_internal(rig):
    res = run_task(rig, 5, "discard")
    assert code(res) == "INTERNAL" and "without an error code" in res.text


@pytest.mark.parametrize("kind, fields, text", [
    ("get_workpiece", {"machine": "C-ZZ"}, "no machine"),
    ("retrieve_cap", {"machine": "C-CS1", "shelf_slot": 0}, "no tree"),     # the test trees have none
])
def test_tasks_that_cannot_run_are_refused(rig, kind, fields, text):
    res = run_task(rig, 6, kind, **fields)
    assert code(res) == "INVALID_TASK" and text in res.text
    assert rig.agent.run is None


def test_one_task_at_a_time_and_resent_tasks(rig):
    srv = rig.server
    srv.task(7, "mount_cap", machine="C-CS1")
    rig.until(lambda: srv.results(7, "RUNNING"))
    srv.task(8, "get_workpiece", machine="C-BS")
    rig.until(lambda: final(srv, 8) is not None)
    assert code(final(srv, 8)) == "INVALID_TASK" and "busy with task 7" in final(srv, 8).text
    node = rig.agent.run.tree.root
    srv.task(7, "mount_cap", machine="C-CS1")                       # the server re-sends the running task
    rig.until(lambda: len(srv.results(7, "RUNNING")) == 2)
    assert rig.agent.run.tree.root is node and node.starts == 1    # not restarted
    srv.cancel(7)
    rig.until(lambda: final(srv, 7) is not None)
    srv.task(8, "get_workpiece", machine="C-BS")                    # accepted once the robot is free
    rig.until(lambda: srv.results(8, "SUCCEEDED"), what="task 8 done")
    srv.task(8, "get_workpiece", machine="C-BS")                    # re-sent after it finished
    rig.until(lambda: len(srv.results(8, "SUCCEEDED")) == 2)
    assert rig.agent.run is None


def test_tasks_for_other_robots_are_ignored(rig):
    rig.server.task(9, "get_workpiece", robot=2, machine="C-BS")
    rig.run(2.0)
    assert rig.server.results(9) == [] and rig.agent.run is None


def test_observations_stream_and_zone_explored_on_success(rig):
    res = run_task(rig, 10, "explore_zone", zone=6)
    assert res.status == TM.TaskResult.SUCCEEDED
    rig.run(0.2)
    obs = [m for m in rig.server.of("MachineObservation") if m.HasField("name")]
    assert len(obs) == 1 and obs[0].name.value == "C-CS1" and obs[0].lights.pattern == 5
    assert obs[0].robot_id == 1 and obs[0].zone.value == 1
    empty = [m for m in rig.server.of("MachineObservation") if m.HasField("searched_zone")]
    assert [(m.searched_zone, m.seen_in_zone) for m in empty] == [(6, False)]   # C-CS1 was seen in Z1
    done = rig.server.of("ZoneExplored")
    assert len(done) == 1 and done[0].zone == 6 and list(done[0].machines) == []
    res = run_task(rig, 11, "explore_zone", zone=1)
    rig.run(0.2)
    assert len(rig.server.of("MachineObservation")) == 2                   # nothing new to say
    assert list(rig.server.of("ZoneExplored")[-1].machines) == ["C-CS1"]


def test_results_wait_for_the_link(rig):
    srv = rig.server
    srv.task(12, "get_workpiece", machine="C-BS")
    rig.until(lambda: srv.results(12, "RUNNING"))
    srv.t.close()                                                   # the team server is gone
    rig.run(3.0)
    assert rig.agent.run is None and not rig.agent.connected
    srv.t = rig.bus.stream_server("ts", registry=TEAM_REG, key=KEY)   # and back
    rig.until(lambda: srv.results(12, "SUCCEEDED"), what="kept result")
    hellos = srv.of("RobotHello")
    assert hellos[-1].restarted is False


def test_shutdown_reports_the_running_task_and_stops(rig):
    srv = rig.server
    srv.task(13, "mount_cap", machine="C-CS1")
    rig.until(lambda: rig.drives()[-1][1] == "drive")
    rig.agent.shutdown("maintenance")
    rig.run(0.2)
    res = final(srv, 13)
    assert code(res) == "INTERNAL" and "maintenance" in res.text
    assert rig.drives()[-1][1] == "stop"


def test_a_silent_team_server_link_is_dropped_and_reconnected(rig):
    srv = rig.server
    rig.run(1.0)
    assert len(srv.of("RobotHello")) == 1 and rig.agent.connected
    srv.heartbeat_every = 10 ** 9          # connected, but the server says nothing any more
    rig.until(lambda: len(srv.of("RobotHello")) == 2, seconds=rig.agent.config.server_timeout + 3,
              what="re-registration after silence")
    assert srv.of("RobotHello")[-1].restarted is False
    srv.heartbeat_every = 20
    rig.run(2.0)
    assert not rig.agent.server_silent


def test_go_to_parameters_from_a_zone_or_a_pose():
    from rll_bt import rules
    from rll_bt.agent import InvalidTask, task_params
    from tests.support.agents import make_task
    prof = rules.profile("rcll2016")
    p = task_params(make_task("go_to", zone=7), prof)
    cx, cy = prof.zone_centre(7)
    assert p["has_target"] is False and p["zone_name"] == prof.zone_name(7)
    assert (p["target"]["x"], p["target"]["y"]) == (cx, cy)
    p = task_params(make_task("go_to", target=TM.Pose2D(x=1.0, y=2.0, theta=0.5)), prof)
    assert p["has_target"] is True and p["zone"] == 0 and p["target"] == {"x": 1.0, "y": 2.0, "theta": 0.5}
    with pytest.raises(InvalidTask):
        task_params(make_task("go_to", zone=99), prof)


def test_a_lost_sensor_fails_the_task_with_its_own_code_and_the_agent_goes_on(rig):
    res = run_task(rig, 40, "go_to", zone=5)
    assert code(res) == "SENSOR_LOST" and "laser lost" in res.text
    assert rig.drives()[-1][1] == "stop"
    assert run_task(rig, 41, "get_workpiece", machine="C-BS").status == TM.TaskResult.SUCCEEDED


def test_a_cancelled_task_given_out_again_runs_again_and_a_late_copy_does_not(rig):
    """The team server cancels a task (its station went down) and later gives the same task id out
    again: the robot runs it, it does not answer with the old CANCELLED (seed 1 lost its product so)."""
    from tests.support.agents import make_task
    srv = rig.server
    first = make_task("mount_cap", 7, machine="C-CS1")
    first.issued_at = 10.0
    assert srv.send(first)
    rig.until(lambda: srv.results(7, "RUNNING"))
    srv.cancel(7)
    rig.until(lambda: srv.results(7, "CANCELLED"))
    assert srv.send(first)                                          # a late copy of the cancelled task
    rig.until(lambda: len(srv.results(7, "CANCELLED")) >= 2, what="the old result told again")
    assert rig.agent.run is None
    again = make_task("get_workpiece", 7, machine="C-BS")
    again.issued_at = 40.0                                          # given out again after the cancel
    assert srv.send(again)
    rig.until(lambda: srv.results(7, "SUCCEEDED"), what="task 7 run again and done")
