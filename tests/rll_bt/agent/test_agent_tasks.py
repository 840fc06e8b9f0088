"""How the agent runs tasks (lockstep, over the in-process bus): outcomes and
their error codes (rll-bt's and the league's), timeouts, bugs in nodes,
refused tasks, tasks that wait, re-sent tasks, pause, observations, results
kept while the link is down."""
from __future__ import annotations

import pytest

from rll_bt.clock import SimClock
from rll_bt.comm import Bus
from tests.support.agents import KEY, LM, TEAM_REG, TM, Rig, ScriptedServer, make_task

STATE = TM.RobotStatus.State


@pytest.fixture
def rig():
    clock = SimClock()
    bus = Bus(clock)
    srv = ScriptedServer(bus.stream_server("ts", registry=TEAM_REG, key=KEY))
    r = Rig(bus.stream_client("ts", registry=TEAM_REG, key=KEY), srv, clock)
    r.bus = bus
    r.until(lambda: r.agent.gate.moving_allowed, what="game running")
    return r


def run_task(rig, tid, kind, seconds=20.0, **fields):
    rig.server.task(tid, kind, **fields)
    rig.until(lambda: rig.server.final(tid) is not None, seconds=seconds, what=f"task {tid} {kind} finished")
    return rig.server.final(tid)


def league(value) -> str:
    return LM.AgentTask.ErrorCode.Name(value)


def test_recovery_runs_and_its_error_code_is_reported(rig):
    res = run_task(rig, 1, "put_workpiece", machine="C-RS1")
    assert res.status == "FAILED" and res.code == "PUT_FAILED"
    assert res.text == "the workpiece is still in the gripper"
    # the league's word for it: the put did not work, the workpiece is still held
    assert league(res.league_code) == "MACHINE_POINT_OCCUPIED" and res.task.successful is False
    assert (res.task.deliver.machine_id, res.task.deliver.machine_point) == ("C-RS1", "input")
    seen = [STATE.Name(s.state) for s in rig.server.of("RobotStatus")]
    assert "RECOVERING" in seen and seen[-1] == "IDLE"


def test_task_timeout_counts_running_time(rig):
    started = rig.clock.now()
    res = run_task(rig, 2, "deliver", machine="C-DS", gate=1, timeout=2.0)
    assert res.code == "TIMEOUT" and "2 s" in res.text and league(res.league_code) == "UNKNOWN"
    assert res.stamp == pytest.approx(started + 2.0, abs=0.25)


def test_a_node_that_raises_fails_the_task_not_the_agent(rig):
    res = run_task(rig, 3, "mount_ring", machine="C-RS1", ring_color="RING_BLUE")
    assert res.code == "INTERNAL" and "node bug" in res.text and league(res.league_code) == "INTERNAL_ERROR"
    assert rig.drives()[-1][1] == "stop"
    assert run_task(rig, 4, "get_workpiece", machine="C-BS").status == "SUCCEEDED"


def test_a_tree_failing_without_a_code_reports_internal(rig):
    res = run_task(rig, 5, "discard")
    assert res.code == "INTERNAL" and "without an error code" in res.text


def test_tasks_that_cannot_run_are_refused_with_the_leagues_code(rig):
    srv = rig.server
    bad = LM.AgentTask(team_color=0, task_id=6, robot_id=1)
    bad.retrieve.machine_id, bad.retrieve.machine_point = "C-ZZ", "output"
    srv.send_agent_task(bad)
    rig.until(lambda: srv.final(6) is not None)
    res = srv.final(6)
    assert res.status == "FAILED" and league(res.league_code) == "INVALID_TARGET" and "no station" in res.text
    res = run_task(rig, 61, "retrieve_cap", machine="C-CS1", shelf_slot=0)     # the test trees have none
    assert res.code == "INVALID_TASK" and "no tree" in res.text
    assert league(res.league_code) == "TASK_NOT_SUPPORTED"
    other = LM.AgentTask(team_color=1, task_id=62, robot_id=1)
    other.move.waypoint = "Z3"
    srv.send_agent_task(other)
    rig.until(lambda: srv.final(62) is not None)
    assert league(srv.final(62).league_code) == "WRONG_TEAM"
    assert rig.agent.run is None


def test_a_task_sent_while_another_runs_waits_and_a_task_id_runs_once(rig):
    """As a league team server expects: the next task (without rll-bt's TaskDetail) waits."""
    srv = rig.server
    srv.task(7, "mount_cap", machine="C-CS1")
    rig.until(lambda: srv.running(7))
    srv.task(8, "get_workpiece", machine="C-BS", detail=False)      # waits for 7
    rig.run(1.0)
    assert srv.final(8) is None and rig.agent.book.where(8) == "waiting"
    node = rig.agent.run.tree.root
    srv.task(7, "mount_cap", machine="C-CS1")                       # the server re-sends the running task
    srv.task(8, "get_workpiece", machine="C-BS", detail=False)      # ... and the waiting one
    rig.run(1.0)
    assert rig.agent.run.tree.root is node and node.starts == 1    # not restarted
    assert len(rig.agent.book.waiting) == 1
    srv.cancel(7)
    rig.until(lambda: srv.final(7) is not None)
    assert srv.final(7).status == "CANCELLED" and srv.final(7).task.canceled
    rig.until(lambda: srv.results(8, "SUCCEEDED"), what="task 8 done")   # then the waiting one
    srv.task(8, "get_workpiece", machine="C-BS", detail=False)      # re-sent after it finished
    rig.until(lambda: len(srv.results(8, "SUCCEEDED")) == 2)
    assert rig.agent.run is None
    assert [e.task_id for e in rig.agent.book.waiting] == []


def test_a_task_sent_to_run_after_the_current_one_starts_once_that_succeeded(rig):
    """rll-bt's team server sends the next task before the current one ends (TaskDetail
    ``after``): it waits, starts when the current one succeeded, and is refused
    (NOT_RUNNING, never begun) when the one before failed, was cancelled or is unknown."""
    srv = rig.server
    srv.task(31, "mount_cap", machine="C-CS1")
    rig.until(lambda: srv.running(31))
    srv.task(32, "go_to", x=1.0, y=2.0, after=31)
    rig.run(1.0)
    assert rig.agent.book.where(32) == "waiting" and srv.final(32) is None
    srv.cancel(31)                                                   # cancelled: not a success
    rig.until(lambda: srv.final(32) is not None)
    res = srv.final(32)
    assert srv.final(31).status == "CANCELLED"
    assert res.status == "FAILED" and res.code == "NOT_RUNNING" and not srv.running(32)
    assert rig.agent.run is None
    srv.task(33, "get_workpiece", machine="C-BS")
    rig.until(lambda: srv.running(33))
    srv.task(34, "get_workpiece", machine="C-BS", after=33)
    rig.until(lambda: srv.running(34), what="task 34 started")
    assert srv.final(33).status == "SUCCEEDED"                        # ... only after 33 succeeded
    rig.until(lambda: srv.final(34) is not None)
    srv.task(35, "put_workpiece", machine="C-RS1")                   # fails (PUT_FAILED)
    srv.task(36, "go_to", x=1.0, y=2.0, after=35)
    rig.until(lambda: srv.final(36) is not None)
    assert srv.final(35).code == "PUT_FAILED" and srv.final(36).code == "NOT_RUNNING" and not srv.running(36)
    srv.task(37, "go_to", x=1.0, y=2.0, after=99)                    # after a task this robot never had
    rig.until(lambda: srv.final(37) is not None)
    assert srv.final(37).code == "NOT_RUNNING" and not srv.running(37)


def test_rll_bts_team_server_gets_a_refusal_from_a_busy_robot(rig):
    """rll-bt's team server (it sends TaskDetail) plans again on a refusal, as it always did."""
    srv = rig.server
    srv.task(21, "mount_cap", machine="C-CS1")
    rig.until(lambda: srv.running(21))
    srv.task(22, "go_to", x=1.0, y=2.0)
    rig.until(lambda: srv.final(22) is not None)
    res = srv.final(22)
    assert res.status == "FAILED" and res.code == "INVALID_TASK"
    assert res.text == "robot 1 is busy with task 21; cancel it first"
    assert rig.agent.run.task_id == 21 and rig.agent.book.where(22) is None


def test_a_waiting_task_can_be_cancelled_and_a_task_paused(rig):
    srv = rig.server
    srv.task(14, "mount_cap", machine="C-CS1")
    srv.task(15, "get_workpiece", machine="C-BS", detail=False)
    rig.until(lambda: srv.running(14))
    srv.cancel(15)
    rig.until(lambda: srv.final(15) is not None)
    assert srv.final(15).status == "CANCELLED" and rig.agent.book.where(15) == "finished"
    from rll_bt.agenttask import render_pause
    srv.send_agent_task(render_pause(14, 1, "CYAN"))
    rig.until(lambda: rig.drives()[-1][1] == "stop", what="paused robot stops")
    ticks = rig.agent.run.ticks
    rig.run(1.0)
    assert rig.agent.run.ticks == ticks and rig.agent.state() == "STOPPED"
    beacon = srv.of("BeaconSignal")[-1]
    assert beacon.task.task_id == 14 and beacon.task.pause_task is True
    srv.send_agent_task(render_pause(14, 1, "CYAN", pause=False))
    rig.run(1.0)
    assert rig.agent.run.ticks > ticks and rig.drives()[-1][1] == "drive"


def test_tasks_for_other_robots_are_refused(rig):
    rig.server.task(9, "get_workpiece", robot=2, machine="C-BS")
    rig.until(lambda: rig.server.final(9) is not None)
    res = rig.server.final(9)
    assert league(res.league_code) == "WRONG_ROBOT" and res.robot_id == 1 and rig.agent.run is None


def test_observations_stream_and_zone_explored_on_success(rig):
    res = run_task(rig, 10, "explore_zone", zone=6)
    assert res.status == "SUCCEEDED"
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
    rig.until(lambda: srv.running(12))
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
    res = srv.final(13)
    assert res.code == "INTERNAL" and "maintenance" in res.text
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


def test_a_robot_held_up_reads_its_link_before_it_calls_the_team_server_silent(rig):
    """The robot's own loop held up longer than server_timeout (a process game on a loaded
    machine: 5-7 s stalls of all agents, each then reconnecting) is no silent server: the
    heartbeats that came meanwhile wait in the link, and the robot reads them first."""
    srv = rig.server
    rig.run(1.0)
    assert len(srv.of("RobotHello")) == 1
    held, tick = [], rig.agent.tick

    def held_up_tick():
        if not held:
            held.append(True)
            srv.heartbeat_every = 1
            for _ in range(14):            # 7 s in this tick; the server talks all along
                rig.clock.advance(0.5)
                srv.pump()
            srv.heartbeat_every = 20
        return tick()
    rig.agent.tick = held_up_tick
    rig.run(3.0)
    assert held and len(srv.of("RobotHello")) == 1 and not rig.agent.server_silent
    assert rig.agent.link.connections == 1


def test_a_lost_sensor_fails_the_task_with_its_own_code_and_the_agent_goes_on(rig):
    res = run_task(rig, 40, "go_to", zone=5)
    assert res.code == "SENSOR_LOST" and "laser lost" in res.text and league(res.league_code) == "INTERNAL_ERROR"
    assert rig.drives()[-1][1] == "stop"
    assert run_task(rig, 41, "get_workpiece", machine="C-BS").status == "SUCCEEDED"


def test_beacons_to_the_team_server_carry_the_current_and_the_finished_tasks(rig):
    srv = rig.server
    srv.task(20, "get_workpiece", machine="C-BS")
    rig.until(lambda: [b for b in srv.of("BeaconSignal") if b.HasField("task")], what="a beacon with the task")
    during = [b for b in srv.of("BeaconSignal") if b.HasField("task")]
    assert during[-1].task.task_id == 20 and during[-1].task.retrieve.machine_id == "C-BS" and during[-1].number == 1
    rig.until(lambda: srv.final(20) is not None)
    rig.run(1.5)
    last = srv.of("BeaconSignal")[-1]
    assert not last.HasField("task")
    assert [(f.TaskId, f.successful) for f in last.finished_tasks][-1] == (20, True)
    assert last.team_name == "Testers" and last.peer_name == "R1" and last.HasField("pose")


def test_a_cancelled_task_given_out_again_runs_again_and_a_late_copy_does_not(rig):
    """The team server cancels a task (its station went down) and later gives the same task id out
    again: the robot runs it, it does not answer with the old CANCELLED (seed 1 lost its product so)."""
    srv = rig.server
    rig.until(lambda: rig.agent.gate.moving_allowed, what="game running")
    at, detail = make_task("mount_cap", 7, machine="C-CS1")
    detail.issued_at = 10.0
    assert srv.send(detail) and srv.send(at)
    rig.until(lambda: srv.running(7), what="task 7 running")
    srv.cancel(7)
    rig.until(lambda: srv.results(7, "CANCELLED"))
    assert srv.send(detail) and srv.send(at)                        # a late copy of the cancelled task
    rig.until(lambda: len(srv.results(7, "CANCELLED")) >= 2, what="the old result told again")
    assert rig.agent.run is None
    at, detail = make_task("get_workpiece", 7, machine="C-BS")
    detail.issued_at = 40.0                                         # given out again after the cancel
    assert srv.send(detail) and srv.send(at)
    rig.until(lambda: srv.results(7, "SUCCEEDED"), what="task 7 run again and done")


def test_a_task_whose_cancel_came_first_is_refused(rig):
    """The cancel overtook its task (a copy repeated or delayed on a faulty link, the
    team server meanwhile gave the task back to the pool): the robot answers the cancel
    and never starts the task that comes after it; it runs the next assignment."""
    srv = rig.server
    srv.cancel(9)
    rig.until(lambda: srv.results(9, "CANCELLED"), what="the cancel answered")
    at, detail = make_task("get_workpiece", 9, machine="C-BS")
    detail.issued_at = 5.0
    assert srv.send(detail) and srv.send(at)                        # the task, late
    rig.until(lambda: len(srv.results(9, "CANCELLED")) >= 2, what="the late task answered as cancelled")
    assert rig.agent.run is None and not srv.running(9)
    run_task(rig, 10, "get_workpiece", machine="C-BS")
