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
        deadline = time.monotonic() + 10
        while not srv.of("RobotHello") and time.monotonic() < deadline:
            server_t.wait(0.05)
            srv.pump()
        hello = srv.of("RobotHello")
        assert hello and hello[0].robot_id == 2 and hello[0].restarted is True
        srv.task(3, "get_workpiece", robot=2, machine="C-BS")
        while not srv.results(3, "SUCCEEDED") and time.monotonic() < deadline:
            server_t.wait(0.05)
            srv.pump()
        assert srv.results(3, "SUCCEEDED")
    finally:
        th.join(timeout=15)
        server_t.close()
    assert rc.get("rc") == 0
