"""``rll-bt teamserver --record`` beside ``rll-bt agent --record``: both ends
of the team-server link record, over real TCP with the team key, the
messages they sent and the ones they received; read back, each message
one end sent is the message the other end received."""
from __future__ import annotations

import socket
import threading

from mcap.reader import make_reader
from mcap_protobuf.decoder import DecoderFactory

from games.replay import JsonDecoderFactory
from rll_bt.cli import main

TEAM, KEY = "Recorders", "rec-key-7"


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def read(path):
    with open(path, "rb") as fh:
        reader = make_reader(fh, decoder_factories=[DecoderFactory(), JsonDecoderFactory()])
        meta = dict(next(m.metadata for m in reader.iter_metadata() if m.name == "rll-bt"))
        msgs = [(ch.topic, d) for _s, ch, _m, d in reader.iter_decoded_messages(log_time_order=True)]
    return meta, msgs


def test_team_server_and_agent_record_both_ends_of_their_link(tmp_path):
    port = free_port()
    rc = {}
    ts = threading.Thread(target=lambda: rc.setdefault("ts", main([
        "teamserver", "--team", TEAM, "--key", KEY, "--listen", f"127.0.0.1:{port}",
        "--state", str(tmp_path / "ts.sqlite"), "--duration", "6", "--record", str(tmp_path / "ts.mcap")])))
    agent = threading.Thread(target=lambda: rc.setdefault("agent", main([
        "agent", "--robot", "2", "--team", TEAM, "--key", KEY, "--backend", "scripted", "--no-refbox",
        "--teamserver", f"127.0.0.1:{port}", "--seconds", "4", "-q", "--record", str(tmp_path / "agent.mcap")])))
    ts.start()
    agent.start()
    agent.join(30)
    ts.join(30)
    assert rc == {"ts": 0, "agent": 0}
    ts_meta, ts_msgs = read(tmp_path / "ts.mcap")
    ag_meta, ag_msgs = read(tmp_path / "agent.mcap")
    assert ts_meta["kind"] == "teamserver" and ag_meta["kind"] == "agent"

    def link(msgs, sender):
        return [(t.rsplit("/", 1)[1], d.SerializeToString()) for t, d in msgs if t.startswith(f"/{sender}/link/")]
    robot_sent, robot_heard = link(ag_msgs, "robot2"), link(ts_msgs, "robot2")
    server_sent, server_heard = link(ts_msgs, "teamserver"), link(ag_msgs, "teamserver")
    assert {"RobotHello", "BeaconSignal"} <= {n for n, _ in robot_sent}
    assert server_sent and server_heard
    # what one end heard is what the other end sent (the agent may stop before the last ones arrive)
    assert [m for m in robot_heard if m in robot_sent] == robot_heard and len(robot_heard) >= len(robot_sent) - 3
    assert [m for m in server_heard if m in server_sent] == server_heard
    hello = next(d for t, d in ts_msgs if t == "/robot2/link/RobotHello")
    assert hello.team_name == TEAM and hello.robot_id == 2
