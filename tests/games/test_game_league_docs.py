"""docs/league.md as another team reads it: its command, ``rll-bt sim --external-team
cyan --teamserver HOST:PORT --team-cyan NAME --key-cyan KEY``, run as a program, and
a team server of the league (tests/support/league_server.py: its own message
classes, framing, crypto and sockets) set up from what that page says and nothing
else: robots connect to it over TCP, it hears the refbox where the page says the
refbox sends, reads its encrypted team channel with the key, prepares a station by
sending where the page says the refbox listens, drives the robots (a base from
the base station onto a ring station's slide: 2 points) and gets the score the
simulator prints at the end."""
from __future__ import annotations

import subprocess
import sys
import time
from pathlib import Path

import pytest

from tests.support.league_server import BASE, LeagueServer
from tests.support.ports import free_port_offset

pytestmark = [pytest.mark.slow, pytest.mark.xdist_group("league-docs")]   # a whole game on the wall clock

TEAM, KEY = "Outsiders", "outsiders-key"
# docs/league.md, "Your team server in rll-bt's world": the refbox sends the public channel to
# 4444 and listens on 4445, cyan 4441/4446; a team server listens where the refbox sends and
# sends where it listens; --refbox-port-offset N moves them all by N
REFBOX_SENDS = {"public": 4444, "cyan": 4441}
REFBOX_LISTENS = {"public": 4445, "cyan": 4446}
PRODUCTION, BS_OUTPUT = 30, 2


@pytest.mark.timeout(900)
def test_another_team_plugs_in_as_docs_league_md_says(tmp_path):
    off = free_port_offset()
    server = LeagueServer(0, ("127.255.255.255", REFBOX_LISTENS["public"] + off, REFBOX_SENDS["public"] + off,
                              REFBOX_LISTENS["cyan"] + off, REFBOX_SENDS["cyan"] + off), TEAM, KEY)
    rll_bt = Path(sys.executable).parent / "rll-bt"
    cmd = [str(rll_bt), "sim", "--profile", "rcll2025", "--external-team", "cyan",
           "--teamserver", f"127.0.0.1:{server.port}", "--team-cyan", TEAM, "--key-cyan", KEY,
           # a short game, three times faster than real time, on ports of its own
           "--robots", "2", "--seed", "8", "--setup", "3", "--exploration", "20", "--production", "300",
           "--speed", "3", "--refbox-port-offset", str(off), "--connect-timeout", "60", "-q"]
    out, err = tmp_path / "out.txt", tmp_path / "err.txt"
    with open(out, "w") as fo, open(err, "w") as fe:
        sim = subprocess.Popen(cmd, stdout=fo, stderr=fe)
    tasks: dict[str, int] = {}
    prepared, robot1 = -100.0, None
    try:
        deadline = time.monotonic() + 600.0
        while sim.poll() is None and time.monotonic() < deadline:
            server.poll()
            time.sleep(0.01)
            phase = server.phase()
            if phase is None or phase[0] != PRODUCTION or {r.number for r in server.robots} != {1, 2}:
                continue
            if "move" not in tasks:                                  # exploration moves, one per robot
                tasks["move"] = server.task(1, move={"waypoint": "C_Z43"})
                tasks["look"] = server.task(2, explore_machine={"machine_id": "C-BS", "machine_point": "output",
                                                                "waypoint": "C_Z63"})
            bs = server.machines.get("C-BS")        # the team channel, read with the key as the page says
            # the 2025 rules take a prepare once the exploration time (20 s here) is over; again if it was not
            if (bs is not None and bs.state == "IDLE" and "get" not in tasks and phase[1] > 22.0
                    and phase[1] > prepared + 5.0 and server.result(tasks["move"]) is not None):
                server.prepare("C-BS", bs=(BS_OUTPUT, BASE["BASE_RED"]))       # sent where the refbox listens
                prepared = phase[1]
            if bs is not None and bs.state == "READY-AT-OUTPUT" and "get" not in tasks:
                tasks["get"] = server.task(1, retrieve={"machine_id": "C-BS", "machine_point": "output"})
            if "get" in tasks and server.result(tasks["get"]) is not None and "slide" not in tasks:   # 2 points
                tasks["slide"] = server.task(1, deliver={"machine_id": "C-RS1", "machine_point": "slide"})
            robot1 = server.robot(1) or robot1           # kept: the link closes when the game ends
        assert sim.wait(timeout=60.0) == 0, err.read_text()[-3000:]
    finally:
        if sim.poll() is None:
            sim.kill()
            sim.wait()
        server.close()
    for name in ("move", "look", "get", "slide"):
        assert name in tasks, (name, tasks, server.machines.get("C-BS"), err.read_text()[-2000:])
        res = server.result(tasks[name])
        assert res is not None and res.successful, (name, res, server.error(tasks[name]))
    beacons = robot1.beacons
    assert any(b.HasField("task") and b.task.task_id == tasks["get"] for b in beacons)            # field 9
    assert any((f.TaskId, f.successful) == (tasks["get"], True) for b in beacons for f in b.finished_tasks)  # 10
    printed = out.read_text().split()                 # "cyan     Outsiders    N points"
    assert printed[:2] == ["cyan", TEAM] and printed[3] == "points", out.read_text()
    assert int(printed[2]) == server.game_state.points_cyan >= 2          # the base on the slide scored
