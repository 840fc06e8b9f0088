"""The team protocol's log in ``--processes`` games: the team server's side of
its TCP link, wall stamps put on the game's clock, the merge with the refbox's
lines, and every robot's task intervals read back from the messages."""
import json
import time

import pytest

from games.teamlog import LoggedStreamServer, WallToSim, merge_into, read_lines, task_runs
from rll_bt import msgs
from rll_bt.clock import SimClock
from rll_bt.comm import MessageRegistry, StreamClient
from rll_bt.comm.msglog import MessageLog

pytestmark = pytest.mark.slow  # whole games: `make test-fast` leaves them out

KEY = "rll-bt-test-key"
TEAM = msgs.message_set("team")


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
    reg = MessageRegistry.from_message_set(TEAM)
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
        task = TEAM.get("Task")(team_color=0, task_id=7, robot_id=2)
        task.explore_zone.zone = 5
        assert server.send(task, to=got[1].source)
        assert server.send(TEAM.get("Heartbeat")(robot_id=0, seq=1))      # to both: two lines
    finally:
        for c in clients:
            c.close()
        server.close()
        log.close()
    lines = read_lines(tmp_path / "team.jsonl")
    assert [(x["from"], x["type"]) for x in lines] == [
        ("R1", "RobotHello"), ("R2", "RobotHello"), ("teamserver", "Task"),
        ("teamserver", "Heartbeat"), ("teamserver", "Heartbeat")]
    assert all(x["channel"] == "teamserver" and x["t"] == 42.0 for x in lines)
    assert lines[2]["msg"]["explore_zone"] == {"zone": 5} and lines[2]["msg"]["robot_id"] == 2


def _line(t, sender, kind, **msg):
    return {"t": t, "channel": "teamserver", "from": sender, "type": kind, "msg": msg}


def test_task_intervals_come_from_tasks_sent_and_results_received():
    lines = [
        _line(1.0, "teamserver", "Task", robot_id=1, task_id=1, team_color="CYAN", explore_zone={"zone": 3}),
        _line(1.1, "R1", "TaskResult", robot_id=1, task_id=1, status="RUNNING"),
        _line(2.0, "teamserver", "Task", robot_id=1, task_id=1, team_color="CYAN", explore_zone={"zone": 3}),
        _line(5.0, "R1", "TaskResult", robot_id=1, task_id=1, status="SUCCEEDED"),
        _line(5.5, "teamserver", "Task", robot_id=2, task_id=2, team_color="CYAN", discard={}),
        _line(6.0, "teamserver", "Task", robot_id=1, task_id=3, team_color="CYAN",
              get_workpiece={"machine": "C-BS"}),
        _line(8.0, "R1", "TaskResult", robot_id=1, task_id=3, status="FAILED", error="GRAB_FAILED"),
        _line(9.0, "teamserver", "Task", robot_id=2, task_id=4, team_color="CYAN", go_to={"zone": 7}),
        _line(9.2, "R2", "TaskResult", robot_id=2, task_id=2, status="CANCELLED"),      # too late: replaced
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
