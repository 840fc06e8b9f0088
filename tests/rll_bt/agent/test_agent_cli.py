"""``rll-bt agent``: arguments, exit codes, and a real run against a scripted
team server on loopback TCP."""
from __future__ import annotations

import socket
import threading
import time

import pytest

from rll_bt.cli import main
from tests.support.agents import KEY, TEAM, ScriptedServer, tcp_server

TREE = """name: get_workpiece
task:
  machine: str
root:
  sequence_with_memory:
    - log: {message: taking from, value: $task.machine}
    - wait: {seconds: 0.3}
"""


def base_args(port, trees, *extra):
    return ["agent", "--robot", "2", "--team", TEAM, "--key", KEY, "--backend", "scripted",
            "--teamserver", f"127.0.0.1:{port}", "--no-refbox", "--trees", str(trees), "-q", *extra]


def serve_one_task(srv, server_t, within: float = 10.0):
    """Wait for the agent's hello, give it task 3 (get a workpiece at the BS) and wait for its result;
    returns the hellos heard."""
    deadline = time.monotonic() + within
    while not srv.of("RobotHello") and time.monotonic() < deadline:
        server_t.wait(0.05)
        srv.pump()
    hello = srv.of("RobotHello")
    if hello:
        srv.task(3, "get_workpiece", robot=2, machine="C-BS")
    while hello and not srv.results(3, "SUCCEEDED") and time.monotonic() < deadline:
        server_t.wait(0.05)
        srv.pump()
    return hello


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


@pytest.fixture
def trees(tmp_path):
    (tmp_path / "get_workpiece.yaml").write_text(TREE)
    return tmp_path


def test_help(capsys):
    with pytest.raises(SystemExit) as exc:
        main(["agent", "--help"])
    assert exc.value.code == 0
    out = capsys.readouterr().out
    for opt in ("--robot", "--team", "--key", "--backend", "--backend-opt", "--teamserver", "--profile", "--color",
                "--refbox-host", "--trees", "--hz"):
        assert opt in out


@pytest.mark.parametrize("key", ["has space", "tab\there"])
def test_a_malformed_key_is_a_usage_error(trees, capsys, key):
    args = base_args(free_port(), trees)
    args[args.index(KEY)] = key
    assert main(args) == 2
    assert "--key" in capsys.readouterr().err


@pytest.mark.parametrize("bad", ["nohost:", ":4460", "host:99999", "host:port"])
def test_a_malformed_team_server_address_is_a_usage_error(trees, bad):
    args = base_args(1, trees)
    args[args.index("127.0.0.1:1")] = bad
    with pytest.raises(SystemExit) as exc:
        main(args)
    assert exc.value.code == 2


def test_an_unknown_team_server_host_exits_3(trees):
    args = base_args(1, trees)
    args[args.index("127.0.0.1:1")] = "no-such-host.invalid:4460"
    assert main(args) == 3


def test_an_unreachable_backend_exits_3(trees, capsys):
    args = base_args(free_port(), trees)
    i = args.index("scripted")
    args[i:i + 1] = ["robotino", "--backend-opt", "device=/dev/rll-bt-no-such-device"]
    assert main(args) == 3
    assert "no-such-device" in capsys.readouterr().err


def test_an_unknown_backend_is_a_usage_error(trees):
    args = base_args(free_port(), trees)
    args[args.index("scripted")] = "no_such_backend"
    assert main(args) == 2


def test_an_invalid_tree_stops_the_start(trees, capsys):
    (trees / "deliver.yaml").write_text("root:\n  no_such_node: {}\n")
    assert main(base_args(free_port(), trees)) == 2
    err = capsys.readouterr().err
    assert "deliver.yaml" in err and "no_such_node" in err


def test_no_team_server_within_the_connect_timeout_exits_3(trees, capsys):
    t0 = time.monotonic()
    assert main(base_args(free_port(), trees, "--connect-timeout", "0.5")) == 3
    assert time.monotonic() - t0 < 10
    assert "team server" in capsys.readouterr().err


def test_runs_a_task_from_a_team_server_over_tcp(trees):
    server_t = tcp_server()
    srv = ScriptedServer(server_t)
    rc = {}
    th = threading.Thread(target=lambda: rc.setdefault("rc", main(base_args(server_t.port, trees, "--seconds", "4"))))
    th.start()
    try:
        hello = serve_one_task(srv, server_t)
        assert hello and hello[0].robot_id == 2 and hello[0].restarted is True
        assert srv.results(3, "SUCCEEDED")
    finally:
        th.join(timeout=15)
        server_t.close()
    assert rc.get("rc") == 0


def test_record_holds_the_robots_trees_and_both_directions_of_its_link(trees, tmp_path):
    """``rll-bt agent --record``: the task's tree tick by tick and the link's messages, decoded."""
    from mcap.reader import make_reader
    from mcap_protobuf.decoder import DecoderFactory

    from games.replay import JsonDecoderFactory
    server_t = tcp_server()
    srv = ScriptedServer(server_t)
    rec = tmp_path / "r2.mcap"
    rc = {}
    th = threading.Thread(target=lambda: rc.setdefault("rc", main(base_args(server_t.port, trees, "--seconds", "4",
                                                                             "--record", str(rec)))))
    th.start()
    try:
        serve_one_task(srv, server_t)
    finally:
        th.join(timeout=15)
        server_t.close()
    assert rc.get("rc") == 0
    with open(rec, "rb") as fh:
        reader = make_reader(fh, decoder_factories=[DecoderFactory(), JsonDecoderFactory()])
        meta = next(m.metadata for m in reader.iter_metadata() if m.name == "rll-bt")
        msgs_ = [(ch.topic, d) for _s, ch, _m, d in reader.iter_decoded_messages(log_time_order=True)]
    assert meta["kind"] == "agent" and meta["robot"] == "2" and meta["clock"] == "wall"
    topics = {t for t, _d in msgs_}
    assert {"/robot2/link/RobotHello", "/robot2/link/AgentTask", "/robot2/link/TaskOutcome",
            "/robot2/link/BeaconSignal", "/teamserver/link/AgentTask", "/teamserver/link/TaskDetail",
            "/robot2/tree/structure", "/robot2/tree"} <= topics, sorted(topics)
    task = next(d for t, d in msgs_ if t == "/teamserver/link/AgentTask")
    assert task.task_id == 3 and task.retrieve.machine_id == "C-BS" and task.retrieve.machine_point == "output"
    structure = next(d for t, d in msgs_ if t == "/robot2/tree/structure")
    assert structure["kind"] == "get_workpiece" and {n["type"] for n in structure["nodes"]} >= {"log", "wait"}
    ticks = [d for t, d in msgs_ if t == "/robot2/tree"]
    assert ticks[-1]["outcome"]["status"] == "SUCCEEDED" and any(d["status"] == "RUNNING" for d in ticks)
    results = [d for t, d in msgs_ if t == "/robot2/link/AgentTask"]
    assert any(r.task_id == 3 and r.successful for r in results)


def test_with_league_a_plain_agenttask_team_server_drives_it(trees):
    server_t = tcp_server(key=None)                   # a league team server: plain frames
    srv = ScriptedServer(server_t, league=True)
    rc = {}
    th = threading.Thread(target=lambda: rc.setdefault(
        "rc", main(base_args(server_t.port, trees, "--seconds", "4", "--league"))))
    th.start()
    try:
        deadline = time.monotonic() + 10
        while srv.client is None and time.monotonic() < deadline:
            server_t.wait(0.05)
            srv.pump()
        while not srv.of("BeaconSignal") and time.monotonic() < deadline:
            server_t.wait(0.05)
            srv.pump()
        assert srv.of("BeaconSignal")[0].number == 2 and not srv.of("RobotHello")
        srv.task(3, "get_workpiece", robot=2, machine="C-BS")
        while not srv.results(3, "SUCCEEDED") and time.monotonic() < deadline:
            server_t.wait(0.05)
            srv.pump()
        assert srv.results(3, "SUCCEEDED")
    finally:
        th.join(timeout=15)
        server_t.close()
    assert rc.get("rc") == 0
    assert {m.DESCRIPTOR.name for _c, m in srv.got} == {"BeaconSignal", "AgentTask"}


def test_record_to_a_place_that_cannot_be_written_is_a_usage_error(trees, tmp_path, capsys):
    blocker = tmp_path / "file"
    blocker.write_text("")
    assert main(base_args(free_port(), trees, "--record", str(blocker / "x.mcap"), "--connect-timeout", "1")) == 2
    assert "--record" in capsys.readouterr().err


def test_network_faults_delay_and_cut_the_team_server_link(trees):
    """--net-cut 0-1.5 --net-delay 0.4: nothing reaches the team server for 1.9 s, then the task runs."""
    server_t = tcp_server()
    srv = ScriptedServer(server_t)
    rc = {}
    args = base_args(server_t.port, trees, "--seconds", "8", "--net-delay", "0.4", "--net-loss", "0.1",
                     "--net-cut", "0-1.5", "--net-seed", "3")
    t0 = time.monotonic()
    th = threading.Thread(target=lambda: rc.setdefault("rc", main(args)))
    th.start()
    try:
        deadline = time.monotonic() + 20
        while not srv.of("RobotHello") and time.monotonic() < deadline:
            server_t.wait(0.02)
            srv.pump()
        assert srv.of("RobotHello") and time.monotonic() - t0 >= 1.9      # cut, then delayed
        assert serve_one_task(srv, server_t, within=20.0) and srv.results(3, "SUCCEEDED")
    finally:
        th.join(timeout=30)
        server_t.close()
    assert rc.get("rc") == 0


@pytest.mark.parametrize("bad", [["--net-loss", "1"], ["--net-cut", "5"], ["--net-jitter", "-0.1"]])
def test_bad_network_faults_are_usage_errors(trees, bad):
    with pytest.raises(SystemExit) as exc:
        main(base_args(1, trees, *bad))
    assert exc.value.code == 2
