"""``rll-bt refbox monitor|send`` end to end on loopback, with the real message sets."""
from __future__ import annotations

import json
import os
import queue
import subprocess
import sys
import threading
import time
from pathlib import Path

import pytest

from rll_bt.cli import main
from tests.support.comm import free_udp_ports

RLL_BT = str(Path(sys.executable).parent / "rll-bt")
TEAM, KEY = "Carologistics", "randomkey"


class Monitor:
    """``rll-bt refbox monitor`` in a subprocess; stderr lines are read as they come."""

    def __init__(self, *args):
        env = dict(os.environ, PYTHONUNBUFFERED="1")
        self.proc = subprocess.Popen([RLL_BT, "refbox", "monitor", *args], stdout=subprocess.PIPE,
                                     stderr=subprocess.PIPE, text=True, env=env)
        self.err: queue.Queue[str] = queue.Queue()
        self.err_lines: list[str] = []
        threading.Thread(target=self._read_err, daemon=True).start()

    def _read_err(self):
        for line in self.proc.stderr:
            self.err.put(line)

    def wait_err(self, text, timeout=15.0):
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            try:
                line = self.err.get(timeout=0.1)
            except queue.Empty:
                continue
            self.err_lines.append(line)
            if text in line:
                return line
        raise AssertionError(f"monitor never said {text!r}; stderr so far: {self.err_lines}")

    def finish(self, timeout=15.0):
        out, _ = self.proc.communicate(timeout=timeout)
        time.sleep(0.05)
        while not self.err.empty():
            self.err_lines.append(self.err.get())
        return self.proc.returncode, [json.loads(line) for line in out.splitlines()], \
            "".join(self.err_lines)


def send(capsys, *args):
    rc = main(["refbox", "send", "--team", TEAM, *args])
    return rc, capsys.readouterr().err


def test_monitor_and_send_on_the_team_channel(capsys):
    pub, team = free_udp_ports(2)
    mon = Monitor("--team", TEAM, "--key", KEY, "--color", "cyan", "--public-recv", str(pub),
                  "--team-recv", str(team), "--count", "2", "--seconds", "20")
    try:
        mon.wait_err("team channel (cyan, encrypted)")
        beacon = {"time": {"sec": "1700000000", "nsec": "5"}, "seq": "1", "number": 2,
                  "team_name": TEAM, "peer_name": "R2", "team_color": "CYAN"}
        rc, err = send(capsys, "--key", KEY, "--color", "cyan", "--team-send", str(team),
                       "--type", "BeaconSignal", "--json", json.dumps(beacon))
        assert rc == 0 and "encrypted" in err
        rc, _ = send(capsys, "--key", "wrongkey", "--color", "cyan", "--team-send", str(team),
                     "--type", "BeaconSignal", "--json", json.dumps(beacon))
        assert rc == 0
        # the console script itself, on the public channel
        gs = {"game_time": {"sec": "12", "nsec": "0"}, "state": "RUNNING",
              "phase": "PRODUCTION", "points_cyan": 5, "team_cyan": TEAM}
        subprocess.run([RLL_BT, "refbox", "send", "--team", TEAM, "--public", "--public-send",
                        str(pub), "--type", "GameState", "--json", json.dumps(gs)], check=True,
                       capture_output=True, timeout=30)
        rc, lines, err = mon.finish()
    finally:
        mon.proc.kill()
    assert rc == 0, err
    assert lines == [{"type": "BeaconSignal", "channel": "team", "msg": beacon},
                     {"type": "GameState", "channel": "public", "msg": gs}]
    assert "1 dropped (decrypt_failure 1)" in err


def test_monitor_learns_the_colour_from_gamestate_rcll2025(capsys):
    pub, team = free_udp_ports(2)
    mon = Monitor("--profile", "rcll2025", "--team", TEAM, "--key", KEY, "--public-recv",
                  str(pub), "--team-recv", str(team), "--count", "2", "--seconds", "20")
    try:
        mon.wait_err("public channel: listening")
        gs = {"game_time": {"sec": "0", "nsec": "0"}, "state": "RUNNING", "phase": "PRODUCTION",
              "team_cyan": "Other", "team_magenta": TEAM, "field_width": 7}
        assert send(capsys, "--profile", "rcll2025", "--public", "--public-send", str(pub),
                    "--type", "GameState", "--json", json.dumps(gs))[0] == 0
        mon.wait_err("team channel (magenta, encrypted)")
        report = {"team_color": "MAGENTA",
                  "machines": [{"name": "M-CS1", "zone": "M_Z43", "rotation": 45}]}
        assert send(capsys, "--profile", "rcll2025", "--key", KEY, "--color", "magenta",
                    "--team-send", str(team), "--type", "MachineReport",
                    "--json", json.dumps(report))[0] == 0
        rc, lines, err = mon.finish()
    finally:
        mon.proc.kill()
    assert rc == 0, err
    assert [(d["type"], d["channel"]) for d in lines] == [("GameState", "public"),
                                                           ("MachineReport", "team")]
    assert lines[1]["msg"] == report


def test_monitor_with_nothing_to_hear_exits_3():
    (pub,) = free_udp_ports(1)
    r = subprocess.run([RLL_BT, "refbox", "monitor", "--team", TEAM, "--key", KEY,
                        "--public-recv", str(pub), "--count", "1", "--seconds", "0.3"],
                       capture_output=True, text=True, timeout=30)
    assert r.returncode == 3 and r.stdout == ""
    assert "received 0 of 1 messages" in r.stderr and "no frames dropped" in r.stderr


@pytest.mark.parametrize("args,needle", [
    (["--type", "GameState", "--json", "{bad"], "--json: bad JSON"),
    (["--type", "GameState", "--json", "[1]"], "expected a JSON object"),
    (["--type", "NoSuchMessage", "--json", "{}"], "unknown message type 'NoSuchMessage'"),
    (["--type", "GameState", "--json", '{"bogus": 1}'], "bogus"),
    (["--type", "GameState", "--json", '{"state": "NOT_A_STATE"}'], "NOT_A_STATE"),
    (["--type", "GameState", "--json", '{"state": "RUNNING"}'], "lacks required field(s)"),
    (["--type", "Time", "--json", "{}"], "has no CompType"),
    (["--profile", "rcll1999", "--type", "GameState"], "unknown profile"),
])
def test_send_input_errors_exit_2_with_one_clear_message(capsys, args, needle):
    rc, err = send(capsys, "--key", KEY, "--color", "cyan", "--team-send", "9", *args)
    assert rc == 2
    assert err.startswith("rll-bt: error:") and needle in err and "Traceback" not in err


def test_send_needs_a_key_for_the_team_channel_and_a_colour_source(capsys):
    rc, err = send(capsys, "--color", "cyan", "--type", "GameState")
    assert rc == 2 and "--key" in err
    (pub,) = free_udp_ports(1)
    rc, err = send(capsys, "--key", KEY, "--public-recv", str(pub), "--wait", "0.2",
                   "--type", "BeaconSignal", "--json",
                   '{"time":{"sec":1,"nsec":0},"seq":1,"number":1,"team_name":"T",'
                   '"peer_name":"R"}')
    assert rc == 3 and "no GameState naming team" in err


def test_send_oversize_is_a_clear_error(capsys):
    big = {"signals": [{"type": "x" * 200, "lights": []} for _ in range(6)]}
    rc, err = send(capsys, "--public", "--public-send", "9", "--type", "ExplorationInfo",
                   "--json", json.dumps(big))
    assert rc == 2 and "over the 1024-byte limit" in err
