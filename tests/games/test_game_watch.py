"""A short game recorded as MCAP and served live over Foxglove's WebSocket
protocol: read back with the ``mcap`` reader (channels, schemas, counts,
poses, scans, camera frames and trees decode), ``rll-bt replay`` draws the
same report, and a WebSocket client sees the channels advertised and
messages arrive while the game runs."""
from __future__ import annotations

import json
import math
import re
import struct
import threading
import time
from pathlib import Path

import cv2
import numpy as np
import pytest
from mcap.reader import make_reader
from mcap_protobuf.decoder import DecoderFactory

from games import GameOptions, LockstepGame
from games.plots import draw_all
from games.replay import JsonDecoderFactory, RecordingError, read, redraw
from rll_bt.cli import main

pytestmark = pytest.mark.slow


class LiveClient(threading.Thread):
    """A Foxglove WebSocket client: subscribes to every advertised channel and counts messages."""

    def __init__(self, port: int):
        super().__init__(daemon=True)
        self.port = port
        self.channels: dict[int, dict] = {}
        self.received: dict[str, int] = {}
        self.first: dict[str, bytes] = {}
        self.stop = threading.Event()
        self.error = None
        self.retries: dict[int, int] = {}      # channel id -> subscriptions the server refused as unknown

    def run(self):
        from websockets.exceptions import ConnectionClosedOK
        from websockets.sync.client import connect
        try:
            with connect(f"ws://127.0.0.1:{self.port}", subprotocols=["foxglove.sdk.v1"], open_timeout=10) as ws:
                subs: dict[int, str] = {}
                while not self.stop.is_set():
                    try:
                        m = ws.recv(timeout=0.2)
                    except TimeoutError:
                        continue
                    if isinstance(m, str):
                        op = json.loads(m)
                        unknown = re.fullmatch(r"Unknown channel ID: (\d+)", op.get("message", ""))
                        if op["op"] == "status" and unknown:
                            # foxglove-sdk files an advertised channel under the client just after sending
                            # the advertisement: a quick subscription can miss it; it is there a moment later
                            cid = int(unknown.group(1))
                            self.retries[cid] = self.retries.get(cid, 0) + 1
                            time.sleep(0.01 * self.retries[cid])
                            ws.send(json.dumps({"op": "subscribe", "subscriptions": [{"id": cid, "channelId": cid}]}))
                        if op["op"] == "advertise":
                            new = []
                            for ch in op["channels"]:
                                self.channels[ch["id"]] = ch
                                subs[ch["id"]] = ch["topic"]
                                new.append({"id": ch["id"], "channelId": ch["id"]})
                            ws.send(json.dumps({"op": "subscribe", "subscriptions": new}))
                    elif m[0] == 1:            # message data: opcode, subscription id, timestamp, payload
                        sub, _ts = struct.unpack_from("<IQ", m, 1)
                        topic = subs.get(sub, "?")
                        self.received[topic] = self.received.get(topic, 0) + 1
                        self.first.setdefault(topic, bytes(m[13:]))
        except ConnectionClosedOK:             # the server stopped with the game
            pass
        except Exception as exc:
            self.error = exc


@pytest.fixture(scope="module")
def played(tmp_path_factory):
    out = tmp_path_factory.mktemp("watch")
    opts = GameOptions(seed=2, robots=2, setup=1.0, exploration=25.0, production=20.0, strategy="oracle",
                       record=out / "game.mcap", live=0, record_camera=0.2)
    game = LockstepGame(opts)
    client = LiveClient(game.watch.port)
    client.start()
    try:
        game.start()
        game.run_for(1.0)
        deadline = time.monotonic() + 10
        while not client.channels and time.monotonic() < deadline:     # the client has connected
            time.sleep(0.05)
        result = game.run()
        time.sleep(0.5)
    finally:
        game.close()              # what the agents say as they shut down is recorded too
        client.stop.set()
        client.join(5)
    frames, undecoded = game.bus.frames, game.watch.undecoded
    return out, opts, result, client, frames, undecoded


def _messages(path: Path):
    with open(path, "rb") as fh:
        reader = make_reader(fh, decoder_factories=[DecoderFactory(), JsonDecoderFactory()])
        summary = reader.get_summary()
        msgs = [(ch.topic, m.log_time, dec) for _s, ch, m, dec in reader.iter_decoded_messages(log_time_order=True)]
    return summary, msgs


def test_the_recording_holds_every_channel(played):
    out, _opts, result, _client, frames, undecoded = played
    summary, _msgs = _messages(out / "game.mcap")
    schemas = {ch.topic: summary.schemas[ch.schema_id].name for ch in summary.channels.values()}
    counts = {summary.channels[cid].topic: n for cid, n in summary.statistics.channel_message_counts.items()}
    for n in (1, 2):
        assert schemas[f"/robot{n}/pose"] == schemas[f"/robot{n}/true_pose"] == "foxglove.PoseInFrame"
        assert schemas[f"/robot{n}/scan"] == "foxglove.LaserScan"
        assert schemas[f"/robot{n}/camera"] == "foxglove.CompressedImage"
        assert schemas[f"/robot{n}/tree"] == "rllbt.TreeTick"
        assert schemas[f"/robot{n}/link/RobotStatus"] == "rllbt.RobotStatus"
        assert schemas[f"/robot{n}/cyan/BeaconSignal"] == "llsf_msgs.BeaconSignal"
        # 10 poses a second of each kind; ticks at 10 Hz while a task runs; scans at most 5 Hz
        assert abs(counts[f"/robot{n}/true_pose"] - 10 * result.sim_time) <= 12
        assert 5 * result.sim_time >= counts[f"/robot{n}/scan"] >= result.sim_time
        assert counts[f"/robot{n}/tree"] >= 5 * result.sim_time
        assert 0.2 * result.sim_time + 2 >= counts[f"/robot{n}/camera"] >= 0.2 * result.sim_time - 2
    assert schemas["/refbox/public/GameState"] == "llsf_msgs.GameState"
    assert schemas["/teamserver/link/AgentTask"] == "llsf_msgs.AgentTask"
    assert schemas["/teamserver/link/TaskDetail"] == "rllbt.TaskDetail"
    assert schemas["/teamserver/cyan/MachineReport"] == "llsf_msgs.MachineReport"
    assert schemas["/field"] == "foxglove.SceneUpdate"
    # every frame that crossed the bus is on a protobuf topic (none failed to decode)
    proto = sum(n for t, n in counts.items()
                if t.count("/") == 3 and t.split("/")[2] in ("public", "cyan", "magenta", "link", "refbox"))
    assert undecoded == 0 and proto == frames
    assert counts["/game/sample"] == len(result.recording.samples)


def test_poses_scans_frames_and_trees_decode(played):
    out, opts, result, *_ = played
    _summary, msgs = _messages(out / "game.mcap")
    f = opts.rules.field
    truth = [d for t, _ns, d in msgs if t == "/robot1/true_pose"]
    est = [d for t, _ns, d in msgs if t == "/robot1/pose"]
    assert all(f.x_min - 0.5 <= p.pose.position.x <= f.x_max + 0.5 for p in truth + est)
    moved = math.hypot(truth[-1].pose.position.x - truth[0].pose.position.x,
                       truth[-1].pose.position.y - truth[0].pose.position.y)
    assert moved > 0.5 and est[-1].frame_id == "field"
    # the estimate follows the truth (the cheap localiser within half a metre at the end)
    assert math.hypot(est[-1].pose.position.x - truth[-1].pose.position.x,
                      est[-1].pose.position.y - truth[-1].pose.position.y) < 0.5
    scan = next(d for t, _ns, d in msgs if t == "/robot1/scan")
    assert len(scan.ranges) > 100 and scan.end_angle > scan.start_angle
    assert sum(1 for r in scan.ranges if math.isfinite(r)) > 50
    cam = next(d for t, _ns, d in msgs if t == "/robot2/camera")
    img = cv2.imdecode(np.frombuffer(cam.data, np.uint8), cv2.IMREAD_COLOR)
    assert cam.format == "jpeg" and img is not None and img.shape[2] == 3 and img.std() > 5
    structure = next(d for t, _ns, d in msgs if t == "/robot1/tree/structure")
    ids = {n["id"] for n in structure["nodes"]}
    ticks = [d for t, _ns, d in msgs if t == "/robot1/tree"]
    assert all(i in ids for d in ticks[:20] if d["task_id"] == structure["task_id"] for i, _s in d["visited"])
    assert any(d.get("bb") for d in ticks) and any(d.get("outcome") for d in ticks)
    assert {d["status"] for d in ticks} >= {"RUNNING", "SUCCESS"}
    gs = [d for t, _ns, d in msgs if t == "/refbox/public/GameState"]
    assert gs[-1].DESCRIPTOR.name == "GameState" and gs[-1].points_cyan == result.status.points["CYAN"]


def test_replay_draws_the_same_report(played, tmp_path, capsys):
    out, opts, result, *_ = played
    rep = read(out / "game.mcap")
    assert rep.recording == result.recording
    assert rep.stations == result.stations and rep.sim_time == result.sim_time
    (tmp_path / "game").mkdir()
    game_pngs = draw_all(opts.rules, result, tmp_path / "game")
    replay_pngs = redraw(rep, tmp_path / "replay")
    assert [p.name for p in replay_pngs] == [p.name for p in game_pngs] and len(game_pngs) == 3
    for a, b in zip(game_pngs, replay_pngs, strict=True):
        assert a.read_bytes() == b.read_bytes(), a.name
    assert main(["replay", str(out / "game.mcap"), "--out", str(tmp_path / "cli")]) == 0
    text = capsys.readouterr().out
    assert "/robot1/scan" in text and "foxglove.LaserScan" in text
    assert f"total score {result.status.points['CYAN']:9d}".replace(" ", "") in text.replace(" ", "")
    assert (tmp_path / "cli" / "timeline.png").read_bytes() == game_pngs[1].read_bytes()


def test_a_recording_cut_short_still_replays(played, tmp_path):
    out, *_ = played
    data = (out / "game.mcap").read_bytes()
    cut = tmp_path / "cut.mcap"
    cut.write_bytes(data[: len(data) // 2])
    try:
        rep = read(cut)
    except RecordingError as exc:          # the reader needs the summary: a clear error, not a traceback
        assert "MCAP" in str(exc) or "recording" in str(exc)
    else:
        assert rep.result is None and rep.recording.samples
    bad = tmp_path / "bad.mcap"
    bad.write_bytes(b"not an mcap file")
    with pytest.raises(RecordingError):
        read(bad)
    assert main(["replay", str(bad)]) == 2


def test_live_clients_see_the_channels_and_the_messages(played):
    _out, _opts, result, client, *_ = played
    assert client.error is None, client.error
    # every channel advertised is subscribed in the end: a refused subscription went through when asked again
    assert all(n <= 2 for n in client.retries.values()), client.retries
    subscribed_late = {client.channels[c]["topic"] for c in client.retries}
    assert all(client.received.get(t) for t in subscribed_late if t.endswith(("pose", "GameState"))), subscribed_late
    topics = {ch["topic"]: ch for ch in client.channels.values()}
    assert topics["/robot1/pose"]["schemaName"] == "foxglove.PoseInFrame"
    assert topics["/refbox/public/GameState"]["encoding"] == "protobuf"
    assert client.received.get("/robot1/true_pose", 0) > 5 * result.sim_time
    assert client.received.get("/refbox/public/GameState", 0) > 10
    from foxglove.messages import PoseInFrame  # noqa: F401 - the schema is foxglove's own
    from mcap_protobuf.schema import build_file_descriptor_set  # noqa: F401
    assert len(client.first["/robot1/pose"]) > 20
