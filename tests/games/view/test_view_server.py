"""The live page's server (the page, its assets, the state and its
server-sent events, a replay's controls), a recording played back, a live
Foxglove server followed, and ``rll-bt view``'s exit codes."""
from __future__ import annotations

import http.client
import json
import socket
import threading
import time
import urllib.error
import urllib.request

import pytest

from games.view import ViewServer, ViewState
from games.view.sources import FoxgloveSource, Playback, read_recording, shown
from rll_bt import msgs
from rll_bt.backend import Pose2D
from rll_bt.cli import main
from rll_bt.watch import Watch

RM = msgs.message_set("rcll2016")


class Clock:
    def __init__(self):
        self.t = 0.0

    def now(self):
        return self.t


def game_state(points):
    gs = RM.get("GameState")(state=2, phase=20, points_cyan=points, team_cyan="T")
    gs.game_time.sec, gs.game_time.nsec = int(points), 0
    return gs


def play_into(watch, clock, seconds=10.0):
    """A robot driving along x at 0.5 m/s and a score that grows, on ``watch``."""
    from rll_bt.backend import LaserScan
    watch.json("/robot1/tree/structure", {"task_id": 1, "kind": "go_to", "name": "go", "nodes": [
        {"id": 0, "parent": None, "depth": 0, "name": "root", "type": "sequence"}]})
    for i in range(int(seconds * 10) + 1):
        clock.t = i * 0.1
        watch.pose("/robot1/true_pose", Pose2D(0.5 * clock.t, 1.0, 0.0))
        watch.json("/robot1/tree", {"task_id": 1, "tick": i, "status": "RUNNING", "visited": [[0, "RUNNING"]],
                                    "running": [0]})
        if i % 10 == 0:
            watch.proto("/refbox/public/GameState", game_state(i // 10))
            import numpy as np
            watch.scan("/robot1/scan", LaserScan(clock.t, -1.0, 0.5, 0.05, 5.0, np.ones(5)), None)


@pytest.fixture(scope="module")
def recording(tmp_path_factory):
    path = tmp_path_factory.mktemp("view") / "game.mcap"
    clock = Clock()
    with Watch(record=path, clock=clock, name="test", meta={"kind": "sim", "profile": "rcll2025", "team": "CYAN"}) as w:
        play_into(w, clock)
    return path


def get(url):
    with urllib.request.urlopen(url, timeout=5) as r:
        return r.status, r.headers.get("Content-Type"), r.read()


def post(url, body):
    req = urllib.request.Request(url, data=json.dumps(body).encode(), method="POST",
                                 headers={"Content-Type": "application/json"})
    try:
        with urllib.request.urlopen(req, timeout=5) as r:
            return r.status, json.loads(r.read())
    except urllib.error.HTTPError as exc:
        return exc.code, json.loads(exc.read())


def events(port):
    """The server-sent events of /events, one parsed ``data:`` at a time."""
    conn = http.client.HTTPConnection("127.0.0.1", port, timeout=5)
    conn.request("GET", "/events")
    resp = conn.getresponse()
    assert resp.status == 200 and resp.getheader("Content-Type") == "text/event-stream"

    def next_event():
        while True:
            line = resp.fp.readline()
            if line.startswith(b"data: "):
                return json.loads(line[6:])
    return conn, next_event


def test_the_recording_gives_the_shown_topics_in_time_order(recording):
    meta, messages = read_recording(recording)
    assert meta["profile"] == "rcll2025" and meta["kind"] == "sim"
    topics = {t for _t, t, _v in messages}
    assert topics == {"/robot1/true_pose", "/robot1/tree", "/robot1/tree/structure", "/refbox/public/GameState"}
    assert [m[0] for m in messages] == sorted(m[0] for m in messages) and messages[-1][0] == pytest.approx(10.0)
    assert not shown("/robot1/scan") and not shown("/robot1/camera") and shown("/robot3/pose")


def test_playback_plays_pauses_and_seeks_back(recording):
    _meta, messages = read_recording(recording)
    state = ViewState("rcll2025")
    pb = Playback(state, messages, speed=20.0, playing=False)
    pb.seek(6.0)
    assert state.data["robots"]["1"]["true_pose"][0] == pytest.approx(3.0)
    epoch = state.epoch
    pb.seek(2.0)                                   # back: the state starts over
    assert state.epoch > epoch and state.data["robots"]["1"]["true_pose"][0] == pytest.approx(1.0)
    assert state.data["score"][-1][1] == 2
    with pytest.raises(ValueError):
        pb.control({"op": "fly"})
    with pytest.raises(ValueError):
        pb.control({"op": "speed", "speed": 0})
    pb.start()
    try:
        pb.control({"op": "play"})
        deadline = time.monotonic() + 10
        while not pb.done and time.monotonic() < deadline:
            time.sleep(0.05)
        assert pb.done and not pb.playing and state.data["playback"]["t"] == pytest.approx(10.0)
        assert state.data["robots"]["1"]["true_pose"][0] == pytest.approx(5.0)
    finally:
        pb.close()


def test_the_server_serves_the_page_the_state_its_changes_and_the_controls(recording):
    _meta, messages = read_recording(recording)
    state = ViewState("rcll2025", meta={"source": "replay"})
    pb = Playback(state, messages, playing=False)
    with ViewServer(state, port=0, control=pb.control) as srv:
        base = f"http://127.0.0.1:{srv.port}"
        code, ctype, body = get(base + "/")
        assert code == 200 and ctype.startswith("text/html") and b"/static/view.js" in body
        code, ctype, body = get(base + "/static/view.js")
        assert ctype.startswith("text/javascript") and b"EventSource" in body
        assert get(base + "/static/view.css")[1].startswith("text/css")
        for bad in ("/static/../server.py", "/static/nope.js", "/static/state.py", "/nothing"):
            with pytest.raises(urllib.error.HTTPError) as exc:
                get(base + bad)
            assert exc.value.code == 404
        snap = json.loads(get(base + "/state")[2])
        assert snap["reset"] and snap["set"]["field"]["profile"] == "rcll2025"
        conn, next_event = events(srv.port)
        try:
            first = next_event()
            assert first["reset"] and first["set"]["robots"]["1"]["true_pose"] == [0.0, 1.0, 0.0]
            assert post(base + "/control", {"op": "seek", "t": 4.0}) == (200, {"t": 4.0, "speed": 1.0,
                                                                               "playing": False})
            change = next_event()
            while "robots/1" not in change.get("set", {}):
                change = next_event()
            assert not change.get("reset") and change["set"]["robots/1"]["true_pose"][0] == pytest.approx(2.0)
            assert change["append"]["paths"]["1"][-1][1] == pytest.approx(2.0)
        finally:
            conn.close()
        assert post(base + "/control", {"op": "fly"})[0] == 400
        assert post(base + "/control", {"op": "seek"})[0] == 400
    live = ViewServer(ViewState(), port=0)
    try:
        assert post(f"http://127.0.0.1:{live.port}/control", {"op": "pause"})[0] == 409
    finally:
        live.close()


def test_a_live_foxglove_server_is_followed(tmp_path):
    clock = Clock()
    watch = Watch(live=0, clock=clock, name="rll-bt sim (rcll2025, seed 3)")
    state = ViewState()
    src = FoxgloveSource(state, f"ws://127.0.0.1:{watch.port}")
    src.start()
    try:
        assert src.connected.wait(10) and src.error is None
        assert state.data["field"]["profile"] == "rcll2025"           # told by the server's name
        def followed() -> bool:  # the robot's last pose and the game's last score have arrived
            robot = state.data["robots"].get("1", {})
            points = state.data["game"].get("points", {})
            return robot.get("true_pose", [None])[0] == pytest.approx(1.5) and points.get("CYAN") == 3

        # the view subscribes channel by channel as the server advertises them: play the same
        # three seconds again until every channel is followed (the deadline only stops a hang)
        deadline = time.monotonic() + 60
        while time.monotonic() < deadline:
            play_into(watch, clock, seconds=3.0)
            time.sleep(0.2)
            if followed():
                break
        assert state.data["robots"]["1"]["true_pose"][0] == pytest.approx(1.5)
        assert state.data["game"]["points"]["CYAN"] == 3 and src.messages > 10
    finally:
        src.close()
        watch.close()


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def test_view_command_exit_codes(recording, tmp_path, capsys):
    assert main(["view", str(recording), "--port", "0", "--seconds", "0.5", "--speed", "50"]) == 0
    assert "open http://localhost:" in capsys.readouterr().err
    junk = tmp_path / "junk.mcap"
    junk.write_bytes(b"not a recording")
    assert main(["view", str(junk), "--port", "0", "--seconds", "0.1"]) == 2
    assert main(["view", str(tmp_path / "missing.mcap"), "--port", "0"]) == 2
    assert main(["view", str(recording), "--speed", "0"]) == 2
    assert main(["view", str(recording), "--profile", "rcll1999"]) == 2
    assert main(["view", f"ws://127.0.0.1:{free_port()}", "--port", "0", "--seconds", "0.1"]) == 3
    with socket.socket() as taken:
        taken.bind(("127.0.0.1", 0))
        taken.listen()
        assert main(["view", str(recording), "--port", str(taken.getsockname()[1]), "--seconds", "0.1"]) == 3
    capsys.readouterr()


def test_a_live_server_that_goes_away_ends_the_view_with_3(capsys):
    watch = Watch(live=0, clock=Clock(), name="rll-bt agent R1 (rcll2016)")
    rc = {}
    th = threading.Thread(target=lambda: rc.setdefault("rc", main(["view", f"ws://127.0.0.1:{watch.port}",
                                                                   "--port", "0", "--seconds", "20"])))
    th.start()
    time.sleep(2.0)
    watch.close()
    th.join(15)
    assert rc.get("rc") == 3 and "closed the connection" in capsys.readouterr().err
