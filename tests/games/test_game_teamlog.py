"""The team protocol's log in ``--processes`` games: the team server's side of
its TCP link, wall stamps put on the game's clock, the merge with the refbox's
lines, and every robot's task intervals read back from the messages."""
import json
import time

import pytest

from games.teamlog import LoggedStreamServer, WallToSim, merge_into, read_lines, task_runs
from rll_bt import msgs
from rll_bt.agenttask import link as agent_link
from rll_bt.clock import SimClock
from rll_bt.comm import StreamClient
from rll_bt.comm.msglog import MessageLog

pytestmark = pytest.mark.slow  # whole games: `make test-fast` leaves them out

KEY = "rll-bt-test-key"
TEAM = msgs.message_set("team")
LEAGUE = msgs.message_set("rcll2025")


def test_wall_stamps_follow_the_world_when_it_falls_behind():
    m = WallToSim()
    for k in range(11):                      # 1 s of wall = 1 s of game
        m.add(100.0 + k * 0.1, 5.0 + k * 0.1)
    m.add(101.5, 6.1)                        # a slow step: the world lost 0.4 s
    for k in range(1, 6):
        m.add(101.5 + k * 0.1, 6.1 + k * 0.1)
    assert m(100.55) == pytest.approx(5.55)
    assert m(101.25) == pytest.approx(6.05)
    assert m(101.7) == pytest.approx(6.3)
    assert m(103.0) == pytest.approx(6.6 + 1.0)           # after the last pair: at the wall's rate
    assert m(99.0) == pytest.approx(4.0)                   # before the first
    assert len(m) < 10                                     # constant stretches are not stored pair by pair
    stamps = [m(100.0 + k * 0.05) for k in range(60)]
    assert stamps == sorted(stamps)


def test_the_team_servers_side_of_the_link_is_logged_with_robot_names(tmp_path):
    reg = agent_link.registry()
    clock = SimClock(start=42.0)
    log = MessageLog(tmp_path / "team.jsonl", clock, {}, reg, line_buffered=True)
    server = LoggedStreamServer(0, registry=reg, key=KEY, host="127.0.0.1", log=log)
    clients = [StreamClient("127.0.0.1", server.port, registry=reg, key=KEY) for _ in range(2)]
    try:
        deadline = time.monotonic() + 10.0
        while len(server.clients()) < 2 and time.monotonic() < deadline:
            server.wait(0.02)
            for c in clients:
                c.receive()
        assert len(server.clients()) == 2
        for n, c in zip((1, 2), clients):
            assert c.send(TEAM.get("RobotHello")(robot_id=n, team_name="GRIPS", peer_name=f"R{n}"))
        got = []
        while len(got) < 2 and time.monotonic() < deadline:
            server.wait(0.02)
            got += server.receive()
        task = LEAGUE.AgentTask(team_color=0, task_id=7, robot_id=2)
        task.explore_machine.machine_id, task.explore_machine.machine_point = "", ""
        task.explore_machine.waypoint = "Z5"
        assert server.send(task, to=got[1].source)
        assert server.send(TEAM.get("Heartbeat")(robot_id=0, seq=1))      # to both: two lines
    finally:
        for c in clients:
            c.close()
        server.close()
        log.close()
    lines = read_lines(tmp_path / "team.jsonl")
    assert [(x["from"], x["type"]) for x in lines] == [
        ("R1", "RobotHello"), ("R2", "RobotHello"), ("teamserver", "AgentTask"),
        ("teamserver", "Heartbeat"), ("teamserver", "Heartbeat")]
    assert all(x["channel"] == "teamserver" and x["t"] == 42.0 for x in lines)
    assert lines[2]["msg"]["explore_machine"]["waypoint"] == "Z5" and lines[2]["msg"]["robot_id"] == 2


def _line(t, sender, type_name, **msg):
    return {"t": t, "channel": "teamserver", "from": sender, "type": type_name, "msg": msg}


def test_task_intervals_come_from_tasks_sent_and_results_received():
    def task(t, robot, tid, kind=None, **body):
        out = [_line(t, "teamserver", "AgentTask", robot_id=robot, task_id=tid, team_color="CYAN", **body)]
        if kind is not None:
            out.insert(0, _line(t, "teamserver", "TaskDetail", robot_id=robot, task_id=tid, kind=kind))
        return out

    def result(t, robot, tid, ok, canceled=False, **extra):
        return _line(t, f"R{robot}", "AgentTask", robot_id=robot, task_id=tid, team_color="CYAN", successful=ok,
                     canceled=canceled, **extra)

    explore = {"explore_machine": {"machine_id": "", "machine_point": "", "waypoint": "Z3"}}
    lines = [
        *task(1.0, 1, 1, "explore_zone", **explore),
        _line(1.5, "R1", "BeaconSignal", number=1, task={"task_id": 1}),
        *task(2.0, 1, 1, "explore_zone", **explore),                          # sent again: the same run
        result(5.0, 1, 1, True, **explore),
        *task(5.5, 2, 2, "discard", move={"waypoint": "Z4"}),
        *task(6.0, 1, 3, None, retrieve={"machine_id": "C-BS", "machine_point": "output"}),   # a league server
        result(8.0, 1, 3, False, error_code=206),
        *task(9.0, 2, 4, "go_to", move={"waypoint": "Z7"}),
        result(9.2, 2, 2, False, canceled=True),                                 # too late: replaced
        _line(9.3, "teamserver", "AgentTask", robot_id=2, task_id=4, team_color="CYAN", cancel_task=True),
        {"t": 9.5, "channel": "cyan", "from": "teamserver", "type": "MachineReport", "msg": {}},
    ]
    runs = task_runs(lines, end=20.0)
    assert runs[1] == [
        {"kind": "explore_zone", "id": 1, "start": 1.0, "end": 5.0, "outcome": "SUCCEEDED"},
        {"kind": "get_workpiece", "id": 3, "start": 6.0, "end": 8.0, "outcome": "FAILED"}]
    assert runs[2] == [
        {"kind": "discard", "id": 2, "start": 5.5, "end": 9.0, "outcome": "CANCELLED"},
        {"kind": "go_to", "id": 4, "start": 9.0, "end": 20.0, "outcome": "running at the end"}]


def test_merging_keeps_one_log_in_time_order(tmp_path):
    path = tmp_path / "messages.jsonl"
    refbox = [{"t": t, "channel": "public", "from": "refbox", "type": "GameState", "msg": {}} for t in (0.5, 2.0, 3.0)]
    path.write_text("".join(json.dumps(e) + "\n" for e in refbox))
    team = tmp_path / "team.jsonl"
    team.write_text("".join(json.dumps(_line(w, "R1", "Heartbeat", robot_id=1, seq=1)) + "\n"
                            for w in (1000.0, 1001.0, 1002.9)) + '{"t": 1003.0, "chan')   # cut off by a kill
    m = WallToSim()
    m.add(999.0, 0.0)
    m.add(1003.0, 4.0)
    assert merge_into(path, read_lines(team, m), shift=0.5) == 6      # the game started at 0.5
    lines = [json.loads(x) for x in path.read_text().splitlines()]
    assert [(x["t"], x["channel"]) for x in lines] == [
        (0.0, "public"), (0.5, "teamserver"), (1.5, "public"), (1.5, "teamserver"), (2.5, "public"),
        (3.4, "teamserver")]


def test_a_task_queued_behind_the_running_one_starts_when_that_one_succeeded():
    """rll-bt's team server sends a robot its next task before the current one ends
    (TaskDetail ``after``): that does not end the current run; the queued one runs from
    the current one's success, and never if it failed."""
    def task(t, tid, kind, after=None):
        detail = {"kind": kind} if after is None else {"kind": kind, "after": after}
        return [_line(t, "teamserver", "TaskDetail", robot_id=1, task_id=tid, **detail),
                _line(t, "teamserver", "AgentTask", robot_id=1, task_id=tid, team_color="CYAN",
                      move={"waypoint": "Z4"})]

    def result(t, tid, ok):
        return _line(t, "R1", "AgentTask", robot_id=1, task_id=tid, team_color="CYAN", successful=ok,
                     canceled=False, move={"waypoint": "Z4"})
    lines = [*task(1.0, 64, "mount_cap"), *task(3.0, 128, "get_workpiece", after=64),
             *task(4.0, 128, "get_workpiece", after=64),                # repeated while queued
             result(6.0, 64, True), result(9.0, 128, True),
             *task(10.0, 192, "deliver"), *task(11.0, 256, "go_to", after=192), result(12.0, 192, False)]
    assert task_runs(lines, end=20.0)[1] == [
        {"kind": "mount_cap", "id": 64, "start": 1.0, "end": 6.0, "outcome": "SUCCEEDED"},
        {"kind": "get_workpiece", "id": 128, "start": 6.0, "end": 9.0, "outcome": "SUCCEEDED"},
        {"kind": "deliver", "id": 192, "start": 10.0, "end": 12.0, "outcome": "FAILED"}]
