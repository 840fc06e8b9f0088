"""A message log stays bounded: past its limit the messages that repeat on a timer are
left out and counted, and every task, result and acknowledgement is still there, so the
task runs a report reads from the log are the same as from a log without a limit."""
import json

from games.teamlog import read_lines, task_runs
from rll_bt import msgs
from rll_bt.agenttask import link as agent_link
from rll_bt.clock import SimClock
from rll_bt.comm.msglog import PERIODIC, MessageLog

TEAM = msgs.message_set("team")
LEAGUE = msgs.message_set("rcll2025")


def _play(log: MessageLog, clock: SimClock, seconds: int) -> None:
    """Three robots' link: heartbeats, statuses and phases every second, a task every 20 s
    (its TaskDetail and AgentTask, done 15 s later: the robot's AgentTask echo), the acknowledgements."""
    for s in range(seconds):
        clock.set(float(s))
        for n in (1, 2, 3):
            log.record("teamserver", f"R{n}", TEAM.get("Heartbeat")(robot_id=n, seq=s, stamp=float(s)))
            log.record("teamserver", f"R{n}", TEAM.get("RobotStatus")(robot_id=n, state=1))
        log.record("teamserver", "teamserver", TEAM.get("GamePhase")())
        tid, robot = s // 20 + 1, 1 + (s // 20) % 3
        if s % 20 == 0:
            log.record("teamserver", "teamserver", TEAM.get("TaskDetail")(robot_id=robot, task_id=tid,
                                                                            kind="explore_zone"))
            task = LEAGUE.AgentTask(team_color=0, task_id=tid, robot_id=robot)
            task.explore_machine.machine_id, task.explore_machine.machine_point = "", ""
            task.explore_machine.waypoint = "Z5"
            log.record("teamserver", "teamserver", task)
        if s % 20 == 15:
            done = LEAGUE.AgentTask(team_color=0, task_id=tid, robot_id=robot, successful=True)
            done.explore_machine.machine_id, done.explore_machine.machine_point = "", ""
            done.explore_machine.waypoint = "Z5"
            log.record("teamserver", f"R{robot}", done)
            ack = TEAM.get("LinkAck")(robot_id=robot)
            ack.items.add(comp_id=8000, msg_type=502, id=tid << 3)
            log.record("teamserver", "teamserver", ack)


def _log(path, limit):
    clock = SimClock()
    log = MessageLog(path, clock, {}, agent_link.registry(), limit=limit)
    _play(log, clock, 600)                                  # a 10-minute game
    log.close()
    return log


def test_past_its_limit_a_log_leaves_out_the_periodic_messages_and_keeps_the_tasks(tmp_path):
    whole = _log(tmp_path / "whole.jsonl", None)
    capped = _log(tmp_path / "capped.jsonl", 50_000)
    size = (tmp_path / "capped.jsonl").stat().st_size
    assert (tmp_path / "whole.jsonl").stat().st_size > 5 * size       # the limit cut it
    all_lines, lines = read_lines(tmp_path / "whole.jsonl"), read_lines(tmp_path / "capped.jsonl")
    kept = [x for x in all_lines if x["type"] not in PERIODIC]
    # past the limit only what is not periodic was written: its bytes on top of the limit
    extra = sum(len(json.dumps(x, separators=(",", ":"))) + 1 for x in kept)
    assert size <= 50_000 + extra + 2000
    # every task, result and acknowledgement is there, in order; the task runs are the same
    assert [x for x in lines if x["type"] not in PERIODIC and x["type"]] == kept
    assert task_runs(lines, end=600.0) == task_runs(all_lines, end=600.0)
    assert len(task_runs(lines, end=600.0)[1]) == 10
    # the log says where it began leaving out and, at the end, how much
    marks = [x for x in lines if x["type"] is None]
    assert len(marks) == 2 and marks[0]["limit"]["bytes"] == 50_000 and marks[0]["limit"]["left_out"] == {}
    counted = sum(marks[-1]["limit"]["left_out"].values())
    assert counted == sum(capped.left_out.values()) == len(all_lines) - len(lines) + 2
    assert set(marks[-1]["limit"]["left_out"]) == {"Heartbeat", "RobotStatus", "GamePhase"}
    assert [x["t"] for x in lines] == sorted(x["t"] for x in lines)
    assert whole.left_out == {}


def test_a_log_under_its_limit_is_written_whole(tmp_path):
    _log(tmp_path / "whole.jsonl", None)
    _log(tmp_path / "big.jsonl", 64 << 20)
    assert (tmp_path / "whole.jsonl").read_bytes() == (tmp_path / "big.jsonl").read_bytes()
