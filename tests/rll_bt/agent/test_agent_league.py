"""The agent under a team server of the league (``league_only``): the league's
messages only, tasks without rll-bt's TaskDetail, no reconnect on a silent
server, the stations found from the refbox's MachineInfo and its own
sightings; and the parts behind it (the task book, the local machine map)."""
from __future__ import annotations

import math

import pytest

from rll_bt import msgs, rules
from rll_bt.agent import Entry, LocalMachines, Result, TaskBook
from rll_bt.backend import Pose2D
from rll_bt.clock import SimClock
from rll_bt.comm import Bus, MessageRegistry
from tests.support.agents import KEY, LM, TEAM, TEAM_REG, TM, Rig, ScriptedServer

P25 = rules.profile("rcll2025")


@pytest.fixture
def league_rig():
    return make_league_rig()


def make_league_rig(backend=None, clock=None):
    clock = clock or SimClock()
    bus = Bus(clock)
    ms = msgs.message_set("rcll2025")
    reg = MessageRegistry.from_message_set(ms)
    public = bus.peer("public", registry=reg, name="refbox")
    cyan = bus.peer("cyan", registry=reg, key=KEY, name="refbox")
    srv = ScriptedServer(bus.stream_server("ts", registry=TEAM_REG), league=True, profile="rcll2025")
    rig = Rig(bus.stream_client("ts", registry=TEAM_REG), srv, clock, backend=backend, profile="rcll2025",
              league_only=True,
              public=bus.peer("public", registry=reg, name="R1"),
              team=lambda color: bus.peer(color.lower(), registry=reg, key=KEY, name="R1"))

    def refbox_round():
        gs = ms.GameState(state=2, phase=30, team_cyan=TEAM)
        gs.game_time.sec, gs.game_time.nsec = 5, 0
        public.send(gs)
        cyan.receive()
    rig.extra.append(refbox_round)
    rig.refbox = (ms, cyan)
    rig.until(lambda: rig.agent.gate.moving_allowed and srv.client is not None, what="game running, connected")
    return rig


def test_a_league_team_server_hears_only_the_leagues_messages(league_rig):
    rig, srv = league_rig, league_rig.server
    srv.task(1, "get_workpiece", machine="C-BS", side="OUTPUT")      # an AgentTask alone, no TaskDetail
    rig.until(lambda: srv.final(1) is not None, what="result")
    assert srv.final(1).status == "SUCCEEDED" and srv.final(1).task.retrieve.machine_id == "C-BS"
    rig.run(2.0)
    names = {m.DESCRIPTOR.full_name for m in srv.of("BeaconSignal") + [m for _c, m in srv.got]}
    assert names == {"llsf_msgs.BeaconSignal", "llsf_msgs.AgentTask"}
    assert srv.of("BeaconSignal")[0].number == 1                       # it said who it is at once
    assert len(srv.results(1)) == 1                                    # no LinkAck asked for, no result repeated


def test_a_league_retrieve_or_buffer_with_a_workpiece_in_the_gripper_fails_with_the_leagues_code():
    """A league team server's retrieve (or buffer) while the robot holds a workpiece is
    not done "at once" (as after a pause of rll-bt's own task): nothing would be taken,
    and a buffer would put the held workpiece on the cap station as its cap carrier."""
    from backends.scripted import ScriptedBackend
    from rll_bt.agenttask import league_value
    clock = SimClock()
    holding = ScriptedBackend({"readings": {"holding": [{"t": 0, "value": True}]}}, clock=clock)
    rig = make_league_rig(holding, clock)
    srv = rig.server
    srv.task(2, "get_workpiece", machine="C-BS", side="OUTPUT")
    srv.task(3, "retrieve_cap", machine="C-CS1", shelf_slot=0)
    rig.until(lambda: srv.final(3) is not None, what="both answered")
    for tid in (2, 3):
        res = srv.final(tid)
        assert res.status == "FAILED" and res.league_code == league_value("WORKPIECE_ALREADY_IN_GRIPPER"), res
    assert rig.agent.run is None and not [c for c in holding.commands if c[1].startswith("gripper")]
    # an empty gripper: the same retrieve runs (and succeeds on the scripted robot)
    empty = make_league_rig()
    empty.server.task(4, "get_workpiece", machine="C-BS", side="OUTPUT")
    empty.until(lambda: empty.server.final(4) is not None, what="answered")
    assert empty.server.final(4).status == "SUCCEEDED"


def test_a_silent_league_team_server_is_not_a_lost_one(league_rig):
    rig = league_rig
    rig.run(rig.agent.config.server_timeout + 3.0)                     # the server never says anything
    assert rig.agent.connected and not rig.agent.server_silent and rig.agent.link.connections == 1


def test_the_stations_come_from_the_refbox_and_from_what_the_robot_saw(league_rig):
    rig = league_rig
    ms, cyan = rig.refbox
    info = ms.MachineInfo(team_color=0)
    info.machines.add(name="C-BS", zone=ms.enum("Zone").Value("C_Z63"), rotation=90)
    info.machines.add(name="C-DS", zone=ms.enum("Zone").Value("C_Z67"))            # no rotation yet
    cyan.send(info)
    rig.run(0.5)
    known = rig.agent.services["machine_map"]
    cx, cy = P25.zone_centre(63)
    assert known["C-BS"].pose == Pose2D(cx, cy, math.radians(90)) and known["C-BS"].zone == 63
    assert known["C-DS"].pose is None and known["C-DS"].zone == 67
    rig.agent.feed.machine("C-DS", pose=Pose2D(5.4, 6.6, 0.5), confidence=0.9)     # seen by the robot
    rig.run(0.5)
    assert rig.agent.services["machine_map"]["C-DS"].pose == Pose2D(5.4, 6.6, 0.5)
    # an explore_machine of a station the robot knows goes to the station's zone
    at = LM.AgentTask(team_color=0, task_id=5, robot_id=1)
    at.explore_machine.machine_id, at.explore_machine.machine_point, at.explore_machine.waypoint = \
        "C-BS", "output", "C_Z11"
    rig.server.send_agent_task(at)
    rig.until(lambda: rig.agent.run is not None and rig.agent.run.task_id == 5, what="explore running")
    assert rig.agent.run.params["zone"] == 63
    rig.until(lambda: rig.server.final(5) is not None)
    assert rig.agent.book.result(5) is not None
    assert any(b.HasField("task") and b.task.explore_machine.machine_id == "C-BS"
               for b in rig.server.of("BeaconSignal"))


def test_local_machines_prefer_what_the_robot_saw():
    lm = LocalMachines(P25, min_confidence=0.5)
    ms = msgs.message_set("rcll2025")
    info = ms.MachineInfo()
    info.machines.add(name="C-RS1", zone=ms.enum("Zone").Value("C_Z24"), rotation=315)
    info.machines.add(name="X-YY", zone=ms.enum("Zone").Value("C_Z24"))             # not a station: skipped
    assert lm.on_machine_info(info) and not lm.on_machine_info(info)                # the same again: no change
    assert lm.known()["C-RS1"].pose.theta == pytest.approx(math.radians(315))
    assert not lm.on_sighting("C-RS1", Pose2D(1.4, 3.5, 0.1), 24, 0.3)              # not sure enough
    assert lm.on_sighting("C-RS1", Pose2D(1.4, 3.5, 0.1), 24, 0.8)
    k = lm.known()["C-RS1"]
    assert k.pose == Pose2D(1.4, 3.5, 0.1) and k.rotation == 315 and k.type == "RS"
    assert set(lm.known()) == {"C-RS1"}


def test_the_task_book_runs_an_id_once_and_keeps_the_last_results():
    book = TaskBook(keep=3)

    def entry(tid):
        return Entry(LM.AgentTask(team_color=0, task_id=tid, robot_id=1), None, "go_to", {})

    def result(tid, ok=True):
        return Result(LM.AgentTask(team_color=0, task_id=tid, robot_id=1, successful=ok),
                      TM.TaskOutcome(task_id=tid, robot_id=1))
    assert book.take(entry(1)) and not book.take(entry(2)) and not book.take(entry(3))
    assert [book.where(t) for t in (1, 2, 3, 4)] == ["current", "waiting", "waiting", None]
    assert book.drop_waiting(3).task_id == 3 and book.where(3) is None
    book.finish(1, result(1))
    assert book.current is None and book.where(1) == "finished" and book.next().task_id == 2
    for tid in (2, 4, 5, 6):
        book.finish(tid, result(tid, ok=tid != 5))
    assert list(book.finished) == [4, 5, 6] and book.result(1) is None            # the oldest forgotten
    assert [r.successful for r in book.finished.values()] == [True, False, True]


def test_the_task_book_runs_a_cancelled_task_again_only_when_given_out_later():
    book = TaskBook()
    at = LM.AgentTask(team_color=0, task_id=7, robot_id=1)
    book.take(Entry(at, TM.TaskDetail(task_id=7, robot_id=1, issued_at=10.0), "go_to", {}))
    cancelled = LM.AgentTask(team_color=0, task_id=7, robot_id=1, successful=False, canceled=True)
    book.finish(7, Result(cancelled, TM.TaskOutcome(task_id=7, robot_id=1)))
    assert not book.given_again(7, TM.TaskDetail(task_id=7, robot_id=1, issued_at=10.0))   # a late copy
    assert not book.given_again(7, None)                                                   # a league copy
    assert book.given_again(7, TM.TaskDetail(task_id=7, robot_id=1, issued_at=30.0))
    book.forget(7)
    assert book.where(7) is None
