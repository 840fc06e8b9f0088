"""``rll-bt refbox sim`` as a subprocess on UDP loopback, and its argument errors."""
from __future__ import annotations

import signal
import socket
import subprocess
import sys
import time
from collections import defaultdict
from pathlib import Path

import pytest

from backends.sim.refbox.messages import enum_name, set_enum
from rll_bt import msgs
from rll_bt.cli import main
from rll_bt.comm import MessageRegistry, StreamClient, UdpPeer
from tests.support.ports import free_port_offset

RLL_BT = str(Path(sys.executable).parent / "rll-bt")
MS = msgs.message_set("rcll2016")
REG = MessageRegistry.from_message_set(MS)


def _free_offset() -> int:
    """A port offset whose sim-layout UDP ports and TCP stream port are all free."""
    return free_port_offset((4441, 4442, 4444, 4445, 4446, 4447), (4444,), host="0.0.0.0")


def _start(*args) -> subprocess.Popen:
    return subprocess.Popen([RLL_BT, "refbox", "sim", *args], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True)


def _listen(proc, public, cyan, got, each=None, seconds=30.0):
    """Collect what arrives on ``public`` and ``cyan`` into ``got`` while ``proc`` runs,
    calling ``each()`` once per poll."""
    deadline = time.monotonic() + seconds
    while proc.poll() is None and time.monotonic() < deadline:
        public.wait(0.05)
        for rec in public.receive():
            got[("public", rec.type_name)].append(rec.msg)
        for rec in cyan.receive():
            got[("cyan", rec.type_name)].append(rec.msg)
        if each is not None:
            each()


@pytest.mark.slow
def test_udp_game_against_a_listening_team():
    off = _free_offset()
    proc = _start("--team-cyan", "Caro", "--key-cyan", "cyan-key", "--team-magenta", "Grips",
                  "--key-magenta", "magenta-key", "--seed", "3", "--port-offset", str(off),
                  "--start", "command", "--phase-lengths",
                  "setup=0.5,exploration=1.5,production=2,overtime=0", "--quit-after-game")
    # a robot's view of the sim layout: listen where the refbox sends, send where it listens
    public = UdpPeer("127.0.0.1", 4445 + off, 4444 + off, registry=REG, channel="public")
    cyan = UdpPeer("127.0.0.1", 4446 + off, 4441 + off, registry=REG, channel="team",
                   key="cyan-key")
    got = defaultdict(list)
    try:
        ctrl = StreamClient("127.0.0.1", 4444 + off, registry=REG)
        deadline = time.monotonic() + 15
        while not ctrl.wait_connected(0.2):
            assert proc.poll() is None and time.monotonic() < deadline, proc.stderr.read()
        start = MS.SetGameState()
        set_enum(start, "state", "RUNNING")
        assert ctrl.send(start)

        def beacon():
            b = MS.BeaconSignal()
            b.time.sec, b.time.nsec, b.seq, b.number = int(time.time()), 0, 1, 1
            b.team_name, b.peer_name = "Caro", "R1"
            cyan.send(b)
        _listen(proc, public, cyan, got, beacon)
        ctrl.close()
        out, err = proc.communicate(timeout=10)
    finally:
        public.close()
        cyan.close()
        if proc.poll() is None:
            proc.kill()
    assert proc.returncode == 0, err
    phases = {enum_name(g, "phase") for g in got[("public", "GameState")]}
    assert {"PRE_GAME", "EXPLORATION", "PRODUCTION"} <= phases       # 1 Hz: SETUP is short
    assert got[("public", "GameState")][-1].team_cyan == "Caro"
    assert got[("public", "ExplorationInfo")] and got[("public", "OrderInfo")]
    assert got[("cyan", "MachineInfo")] and got[("cyan", "MachineReportInfo")]
    assert cyan.stats.count("decrypt_failure") == 0
    assert any(r.name == "R1" for ri in got[("public", "RobotInfo")] for r in ri.robots)
    lines = out.splitlines()
    assert "waiting for SetGameState" in out
    assert [ln.split("] ")[1].split("  ")[0] for ln in lines if ln.startswith("[")] == [
        "PRE_GAME -> SETUP", "SETUP -> EXPLORATION", "EXPLORATION -> PRODUCTION",
        "PRODUCTION -> POST_GAME"]
    final = next(i for i, ln in enumerate(lines) if ln.startswith("final score:"))
    assert lines[final].startswith("final score: Caro 0 : 0 Grips (POST_GAME")
    assert lines[final + 1:] == ["Caro (CYAN): stations broken 0; referee calls 0",
                                 "Grips (MAGENTA): stations broken 0; referee calls 0"]


def test_udp_2025_game_explores_inside_production():
    ms = msgs.message_set("rcll2025")
    reg = MessageRegistry.from_message_set(ms)
    off = _free_offset()
    proc = _start("--profile", "rcll2025", "--team-cyan", "Caro", "--key", "cyan-key",
                  "--seed", "4", "--port-offset", str(off), "--phase-lengths",
                  "setup=0.5,exploration=1.5,production=3,overtime=0", "--quit-after-game")
    public = UdpPeer("127.0.0.1", 4445 + off, 4444 + off, registry=reg, channel="public")
    cyan = UdpPeer("127.0.0.1", 4446 + off, 4441 + off, registry=reg, channel="team",
                   key="cyan-key")
    got = defaultdict(list)
    try:
        _listen(proc, public, cyan, got)
        out, err = proc.communicate(timeout=10)
    finally:
        public.close()
        cyan.close()
        if proc.poll() is None:
            proc.kill()
    assert proc.returncode == 0, err
    phases = {enum_name(g, "phase") for g in got[("public", "GameState")]}
    assert "PRODUCTION" in phases and "EXPLORATION" not in phases
    assert got[("cyan", "MachineReportInfo")] and not got[("public", "ExplorationInfo")]
    names = {m.name for mi in got[("cyan", "MachineInfo")] for m in mi.machines}
    assert names == {f"C-{t}" for t in ("BS", "DS", "SS", "RS1", "RS2", "CS1", "CS2")}
    assert all(o.HasField("competitive") for oi in got[("public", "OrderInfo")] for o in oi.orders)
    lines = out.splitlines()
    assert lines[0].startswith("refbox sim: rcll2025, seed 4")
    assert [ln.split("] ")[1].split("  ")[0] for ln in lines if ln.startswith("[")] == [
        "PRE_GAME -> SETUP", "SETUP -> PRODUCTION",
        "exploration time over: every machine counts as reported", "PRODUCTION -> POST_GAME"]


def test_sigterm_ends_cleanly():
    off = _free_offset()
    proc = _start("--team-cyan", "Caro", "--key", "k", "--port-offset", str(off),
                  "--world", "table", "--start", "command")
    try:
        line = proc.stdout.readline()
        assert line.startswith("refbox sim: rcll2016"), proc.stderr.read()
        proc.send_signal(signal.SIGTERM)
        out, err = proc.communicate(timeout=10)
    finally:
        if proc.poll() is None:
            proc.kill()
    assert proc.returncode == 0, err
    assert "final score: Caro 0 : 0 - (PRE_GAME, stopped by signal" in out
    assert "Traceback" not in err


@pytest.mark.parametrize("args,where", [
    (["--team-cyan", "A", "--key-cyan", "k", "--phase-lengths", "setup=x"], "--phase-lengths"),
    (["--team-cyan", "A", "--key-cyan", "k", "--profile", "rcll1999"], "--profile"),
    (["--team-cyan", "A", "--key-cyan", "k", "--team-magenta", "B"], "--team-magenta"),
    (["--team-cyan", "A", "--key-cyan", "k", "--speed", "0"], "--speed"),
    (["--team-cyan", "A", "--key-cyan", "k", "--key", "other"], "--key"),   # cyan's key twice
    (["--team-cyan", "A"], "--key"),                                          # no key for cyan
    (["--team-cyan", "A", "--key", "k", "--key", "=x"], "--key"),
])
def test_bad_arguments_exit_2_with_one_line(args, where, capsys):
    assert main(["refbox", "sim", *args]) == 2
    err = capsys.readouterr().err
    assert err.startswith(f"rll-bt: error: {where}") and "Traceback" not in err


def test_busy_stream_port_exits_3(capsys):
    off = _free_offset()
    blocker = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
    blocker.bind(("0.0.0.0", 4444 + off))
    blocker.listen(1)
    try:
        rc = main(["refbox", "sim", "--team-cyan", "A", "--key-cyan", "k", "--world", "table",
                   "--port-offset", str(off)])
    finally:
        blocker.close()
    assert rc == 3 and "cannot open the refbox ports" in capsys.readouterr().err
