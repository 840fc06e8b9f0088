"""``rll-bt teamserver --record`` beside ``rll-bt agent --record``: both ends
of the team-server link record, over real TCP with the team key, the
messages they sent and the ones they received; read back, each message
one end sent is the message the other end received."""
from __future__ import annotations

import signal
import socket
import subprocess
import sys
import time
from pathlib import Path

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


def wait_listening(port: int, proc, timeout: float = 120.0) -> None:
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        assert proc.poll() is None, f"the team server exited ({proc.returncode})"
        try:
            socket.create_connection(("127.0.0.1", port), timeout=1.0).close()
            return
        except OSError:
            time.sleep(0.1)
    raise AssertionError(f"the team server did not listen on {port} within {timeout} s")


def test_team_server_and_agent_record_both_ends_of_their_link(tmp_path):
    # the team server outlives the agent whatever the machine's load: it is up before the agent
    # starts and stopped (SIGTERM, which closes its recording like the end of --duration) after
    port = free_port()
    ts = subprocess.Popen([str(Path(sys.executable).parent / "rll-bt"),
                           "teamserver", "--team", TEAM, "--key", KEY, "--listen", f"127.0.0.1:{port}",
                           "--state", str(tmp_path / "ts.sqlite"), "--record", str(tmp_path / "ts.mcap")],
                          stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    try:
        wait_listening(port, ts)
        rc = main(["agent", "--robot", "2", "--team", TEAM, "--key", KEY, "--backend", "scripted",
                   "--no-refbox", "--teamserver", f"127.0.0.1:{port}", "--seconds", "4", "-q",
                   "--record", str(tmp_path / "agent.mcap")])
        time.sleep(0.5)                        # the agent's last frames reach the server
        ts.send_signal(signal.SIGTERM)
        out, _ = ts.communicate(timeout=60)
    finally:
        if ts.poll() is None:
            ts.kill()
    assert rc == 0 and ts.returncode == 0, out
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
