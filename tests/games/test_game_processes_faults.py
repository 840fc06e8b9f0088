"""Faults in a ``--processes`` game: a refbox process, a team server process and two
``rll-bt agent`` processes on loopback TCP/UDP, the world in the test's process serving
the robots' backends and the refbox's stations.  One short game takes the faults in turn
(each process start costs seconds)."""
import json
import math
import os
import signal
import time

import pytest

from games import GameOptions, finish
from games.processes import ProcessGame
from games.teamlog import read_lines
from rll_bt import rules
from teamserver.knowledge.kb import KnowledgeBase
from teamserver.knowledge.store import Store
from teamserver.links.agents import from_wire
from tests.support.games import PRODUCTION_KINDS

pytestmark = pytest.mark.slow  # whole games: `make test-fast` leaves them out


def _tasks(game) -> dict[int, dict]:
    return {t["id"]: t for t in game.snapshot().get("tasks", [])}


def _working(game) -> dict[int, int]:
    """Robot -> id of the production task the team server has it on."""
    robots = game.snapshot().get("robots", {})
    return {int(n): r["task_id"] for n, r in robots.items() if r.get("task") in PRODUCTION_KINDS}


class _OnDisk:
    """Whether an agent process's recording part holds, on disk, a pose it stamped
    ``age`` seconds or more ago (its writer puts whole chunks in the file, so a
    process killed before its first chunk leaves nothing to keep); the part is
    read again only when it grew."""

    def __init__(self, path, age: float = 3.0):
        self.path, self.age, self.size, self.oldest = path, age, -1, None

    def __call__(self) -> bool:
        from games.procwatch import _records
        size = self.path.stat().st_size if self.path.exists() else 0
        if size != self.size:
            self.size = size
            _meta, _schemas, channels, messages = _records(self.path)
            poses = {c.id for c in channels.values() if c.topic.endswith("/pose")}
            stamps = [m.log_time for m in messages if m.channel_id in poses]
            self.oldest = min(stamps) if stamps else None
        return self.oldest is not None and self.oldest < time.time_ns() - self.age * 1e9


def _stored(path) -> dict:
    """Everything the team server's database holds, item by item (read-only)."""
    store = Store(path, readonly=True)
    try:
        kb = KnowledgeBase.load(rules.profile("rcll2016"), store)
        return {"observations": list(store.observations()),
                "tasks": {i: t.to_dict() for i, t in kb.tasks.items()},
                "products": {i: p.to_dict() for i, p in kb.products.items()},
                "workpieces": {i: w.to_dict() for i, w in kb.workpieces.items()},
                "orders": {i: o.to_dict() for i, o in kb.orders.items()},
                "locks": kb.get("locks"), "reported": dict(kb.reported), "visited": dict(kb.visited),
                "color": kb.get("team_color")}
    finally:
        store.close()


def _same(before: dict, after: dict) -> None:
    for part, items in before.items():
        if isinstance(items, dict):
            missing = sorted(set(items) - set(after[part]), key=str)
            assert not missing, f"{part} lost by the kill: {missing}"
            changed = [k for k in items if items[k] != after[part][k]]
            assert not changed, f"{part} changed by the kill: {changed}"
        assert items == after[part], part


def _beacons(log) -> set[str]:
    """The robots whose beacons the refbox process logged in ``log``."""
    lines = log.read_text().splitlines() if log.exists() else []
    return {json.loads(x).get("msg", {}).get("peer_name") for x in lines if '"BeaconSignal"' in x}


def _confident(game, robot, since) -> list[dict]:
    """The restarted agent's confident RobotStatus messages the team servers logged so far, after ``since``."""
    return [e for logs in game._team_logs.values() for path in logs for e in read_lines(path, game.time_map)
            if e.get("type") == "RobotStatus" and e.get("from") == f"R{robot}" and e["t"] - game._t0 >= since
            and (e.get("msg") or {}).get("pose_confidence", 0) >= 0.5 and "pose" in e["msg"]]


def _relocalised(log, rec, robot, since) -> list[float]:
    """How far each confident pose the restarted agent reported was from the robot's true one."""
    path = rec.paths[robot]
    errors = []
    for x in log:
        if x["type"] != "RobotStatus" or x["from"] != f"R{robot}" or x["t"] < since + 20.0:
            continue
        m = x["msg"]
        if m.get("pose_confidence", 0) < 0.5 or "pose" not in m:
            continue
        t, px, py = min(path, key=lambda p: abs(p[0] - x["t"]))
        if abs(t - x["t"]) < 1.0:
            errors.append(math.hypot(px - m["pose"]["x"], py - m["pose"]["y"]))
    return errors


@pytest.mark.timeout(1200)      # five processes started and restarted: slow on a loaded 2-core machine
def test_agent_killed_and_back_team_server_restarted_station_down(tmp_path):
    opts = GameOptions(seed=3, robots=2, setup=1.0, exploration=3.0, production=300.0, strategy="oracle",
                       processes=True, out=tmp_path / "game", record=tmp_path / "game.mcap")
    game = ProcessGame(opts, connect_timeout=300.0)       # processes start slowly on a loaded machine
    try:
        # the refbox is a process of its own, neither this one (the world's) nor another child
        refbox = game.procs["refbox"].pid
        assert refbox != os.getpid() and refbox not in {p.pid for n, p in game.procs.items() if n != "refbox"}
        assert json.loads(game.refbox_file.read_text())["pid"] == refbox
        # (and the agents' recordings hold poses on disk: the victim's must outlive its SIGKILL)
        parts = [_OnDisk(game.watch.parts / "agent1.mcap"), _OnDisk(game.watch.parts / "agent2.mcap")]
        assert game.run_until(lambda g: bool(_working(g)) and all(p() for p in parts), limit=90.0), \
            "no production task was handed out, or no agent recorded a pose"

        # an agent process dies without a goodbye: its task goes back, the game goes on
        victim, tid = sorted(_working(game).items())[0]
        game.kill_agent(victim)

        def taken_back(g):
            return (g.snapshot()["robots"][str(victim)]["status"] == "LOST"
                    and _tasks(g)[tid]["robot"] != victim)
        assert game.run_until(taken_back, limit=60.0), "the dead robot kept its task"
        st = game.refbox.status()
        assert st.phase == "PRODUCTION" and st.state == "RUNNING"

        # a new agent process for that robot rejoins, not told where it is: it localises globally
        game.start_agent(victim, known_pose=False)
        restarted_at = game.clock.now() - game._t0
        # (a process takes long to start on a loaded machine: the limits are generous)
        assert game.run_until(lambda g: g.snapshot()["robots"][str(victim)]["status"] == "ACTIVE", limit=150.0)
        # ... and production goes on: a product's step is under way when the team server dies
        assert game.run_until(lambda g: any(t["state"] == "ASSIGNED" and t["product"] for t in _tasks(g).values()),
                              limit=150.0), "no production step under way"

        # the team server process is killed mid-production and a new one resumes from the database:
        # frozen first (SIGSTOP) to read what it had committed, then SIGKILLed and read again
        db = game.dir / "teamserver.sqlite"
        game.procs["teamserver"].send_signal(signal.SIGSTOP)
        frozen = _stored(db)
        assert frozen["observations"] and frozen["locks"] and frozen["reported"]
        assert any(p["state"] == "ACTIVE" for p in frozen["products"].values()), "no product in progress"
        assert any(t["state"] == "ASSIGNED" for t in frozen["tasks"].values())
        killed = {}
        before = set(_tasks(game))
        killed_at = game.wall.now()
        game.restart_teamserver(between=lambda: killed.update(_stored(db)))
        _same(frozen, killed)                                  # nothing the server had was lost

        def resumed(g):
            snap = g.snapshot()
            ts = snap.get("tasks", [])
            return (snap.get("now", 0) > killed_at
                    and all(snap["robots"].get(str(n), {}).get("status") == "ACTIVE" for n in (1, 2))
                    and any((t["assigned_at"] or 0) > killed_at or (t["finished_at"] or 0) > killed_at
                            for t in ts))
        assert game.run_until(resumed, limit=150.0), "the new team server neither heard results nor gave tasks"
        assert before <= set(_tasks(game))                                 # the plan survived
        resumed_db = _stored(db)
        assert set(frozen["tasks"]) <= set(resumed_db["tasks"])
        assert set(frozen["products"]) <= set(resumed_db["products"])
        assert len(resumed_db["observations"]) >= len(frozen["observations"])
        done = {i for i, t in frozen["tasks"].items() if t["state"] == "DONE"}
        assert {i for i in done if resumed_db["tasks"][i]["state"] == "DONE"} == done    # nothing done is redone
        for pid, p in frozen["products"].items():        # products in progress: their steps as they were
            assert set(p["tasks"]) <= set(resumed_db["products"][pid]["tasks"]), pid

        # a station goes DOWN: the team server hears it and sends nobody there meanwhile
        down_at = game.wall.now()
        game.station_down("C-BS", 12.0)
        assert game.run_until(lambda g: g.snapshot().get("stations", {}).get("C-BS") == "DOWN", limit=10.0)
        game.run_for(7.0)
        sent = [t for t in _tasks(game).values() if t["machine"] == "C-BS" and t["assigned_at"] is not None
                and down_at + 2.0 < t["assigned_at"] < down_at + 10.0]
        assert not sent, f"tasks sent to C-BS while it was down: {sent}"

        # the refbox process dies and a new one comes up on the same ports (its game starts afresh):
        # the team server hears it (its phases) and its reports score; the robots' beacons reach it
        game.restart_refbox()

        def rejoined(g):
            st = g.refbox.status()
            heard = g.snapshot().get("phase") == "PRODUCTION"
            return st.phase == "PRODUCTION" and st.points.get("CYAN", 0) > 0 and heard
        assert game.run_until(rejoined, limit=150.0), f"not re-joined: {game.refbox.status()}"
        assert game.run_until(lambda g: {"R1", "R2"} <= _beacons(g.dir / "refbox-messages-2.jsonl"), limit=30.0), \
            "the restarted refbox heard no beacon of a robot"
        # (the later a restart, the less game is left: wait for the new agent's confident poses)
        assert game.run_until(lambda g: len(_confident(g, victim, restarted_at + 20.0)) >= 5, limit=120.0), \
            "the restarted agent reported no confident pose"
        result = game.result(False)
    finally:
        game.close()

    summary = finish(result, opts)
    assert summary["team_server_restarts"] == 1
    assert [e["what"] for e in summary["events"]][:5] == ["agent killed", "agent started", "team server restarted",
                                                          "station down", "refbox restarted"]  # (+ the world's lag)
    runs = result.recording.tasks[victim]
    assert any(from_wire(r["id"])[0] == tid and r["outcome"] == "agent killed" for r in runs)   # (wire ids)
    log = [json.loads(x) for x in (opts.out / "messages.jsonl").read_text().splitlines()]
    hellos = [x for x in log if x["type"] == "RobotHello" and x["from"] == f"R{victim}"]
    assert len(hellos) >= 2 and any(x["msg"]["restarted"] for x in hellos[1:])   # the new agent came back
    assert [x["t"] for x in log] == sorted(x["t"] for x in log)
    errors = _relocalised(log, result.recording, victim, restarted_at)
    assert errors and max(errors[-5:]) < 0.5, f"the restarted agent did not localise: {errors[-5:]}"
    assert "DOWN" in {s for _, s in result.recording.stations["C-BS"]}   # the refbox process's states, recorded here
    assert "Traceback" not in (opts.out / "refbox.log").read_text()
    # the recording holds the killed agent's part (cut off by SIGKILL) and its successor's
    from games.replay import read
    rep = read(opts.record)
    assert rep.recording == result.recording
    events = {e["what"]: e["t"] for e in result.recording.events}
    from mcap.reader import make_reader
    with open(opts.record, "rb") as fh:
        reader = make_reader(fh)
        base = int(next(m.metadata for m in reader.iter_metadata() if m.name == "rll-bt")["base_ns"])
        poses = [(m.log_time - base) / 1e9 for _s, _c, m in reader.iter_messages(topics=[f"/robot{victim}/pose"])]
    assert any(t < events["agent killed"] - 1.0 for t in poses)
    assert any(t > events["agent started"] + 5.0 for t in poses)
    assert not any(events["agent killed"] + 0.5 < t < events["agent started"] for t in poses)   # nobody estimated
