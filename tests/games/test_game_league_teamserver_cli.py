"""``rll-bt teamserver --robots agenttask`` as a program (docs/league.md, "rll-bt's team
server for any AgentTask robot"): started beside ``rll-bt sim --external-team cyan``
(another program), both on refbox ports of their own (``--refbox-port-offset``), it
takes the simulated robots that connect to its ``--listen`` port, hears the refbox
on the loopback broadcast, sends the robots exploring over nothing but AgentTask,
learns the stations from the refbox once the exploration time is over and has the
robots take workpieces at them."""
from __future__ import annotations

import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from rll_bt.comm import free_ports
from tests.support.ports import free_port_offset

pytestmark = [pytest.mark.slow, pytest.mark.xdist_group("league-docs")]   # a short game on the wall clock

TEAM, KEY = "Leaguers", "league-key"
EXPLORATION = 30.0      # the first seconds of PRODUCTION under the 2025 rules


@pytest.mark.timeout(600)
def test_the_team_server_command_drives_the_league_simulators_robots(tmp_path):
    from teamserver.status import load
    off = free_port_offset()
    listen = free_ports(1, tcp=True)[0]
    rll_bt = str(Path(sys.executable).parent / "rll-bt")
    state = tmp_path / "ts.sqlite"
    ts_cmd = [rll_bt, "teamserver", "--profile", "rcll2025", "--team", TEAM, "--key", KEY,
              "--robots", "agenttask", "--listen", f"127.0.0.1:{listen}", "--refbox-host", "127.255.255.255",
              "--refbox-port-offset", str(off), "--state", str(state)]
    sim_cmd = [rll_bt, "sim", "--profile", "rcll2025", "--external-team", "cyan",
               "--teamserver", f"127.0.0.1:{listen}", "--team-cyan", TEAM, "--key-cyan", KEY,
               "--seed", "8", "--setup", "3", "--exploration", str(EXPLORATION), "--production", "90",
               "--refbox-port-offset", str(off), "--connect-timeout", "60", "-q"]
    logs = {name: (tmp_path / f"{name}.out", tmp_path / f"{name}.err") for name in ("ts", "sim")}

    def start(name, cmd):
        out, err = logs[name]
        with open(out, "w") as fo, open(err, "w") as fe:
            return subprocess.Popen(cmd, stdout=fo, stderr=fe)

    def tail(name):
        return logs[name][1].read_text()[-3000:]

    ts = start("ts", ts_cmd)
    sim = None
    try:
        time.sleep(1.0)            # listening (the robots would keep reconnecting anyway)
        assert ts.poll() is None, tail("ts")
        sim = start("sim", sim_cmd)
        assert sim.wait(timeout=400.0) == 0, (tail("sim"), tail("ts"))
        assert ts.poll() is None, tail("ts")
        ts.send_signal(signal.SIGTERM)          # stops like at the end of --duration
        assert ts.wait(timeout=30.0) == 0, tail("ts")
    finally:
        for p in (ts, sim):
            if p is not None and p.poll() is None:
                p.kill()
                p.wait()
    assert f"listening on 127.0.0.1:{listen} for agenttask robots" in logs["ts"][1].read_text()
    printed = logs["sim"][0].read_text().split()             # "cyan     Leaguers    N points"
    assert printed[:2] == ["cyan", TEAM] and printed[3] == "points", logs["sim"][0].read_text()
    kb = load(str(state))
    try:
        assert kb.meta.get("team_color") == "CYAN"               # the refbox's team channel, heard
        assert sorted(kb.robots) == [1, 2, 3]                    # the league robots, by their beacons
        tasks = list(kb.tasks.values())
        # exploration first (explore_machine to the robots), then production once the refbox
        # gave the stations away: robots took workpieces at the stations the server chose
        assert any(t.kind == "explore_zone" and t.robot in (1, 2, 3) for t in tasks)
        taken = [t for t in tasks if t.kind in ("get_workpiece", "retrieve_cap") and t.state == "DONE"]
        assert taken and {t.robot for t in taken} <= {1, 2, 3}, [(t.kind, t.robot, t.state, t.error) for t in tasks]
        # no sightings from such robots: the stations come from the refbox after the exploration time
        assert len([s for s in kb.stations.values() if s.zone]) >= 7, kb.stations
    finally:
        kb.store.close()


@pytest.mark.timeout(300)
def test_the_team_server_command_gives_a_robot_its_first_task_and_stops_on_ctrl_c(tmp_path):
    """Short: ``rll-bt teamserver --robots agenttask`` as a program, the league
    simulator's robot in this process (games.league_sim.ExternalGame on the refbox
    ports moved by a free offset): the robot connects, gets an explore task over
    AgentTask and finishes it; Ctrl-C (SIGINT) then stops the server with exit code
    130, its state database kept; ``--help`` names the option and exits 0."""
    from games.league_sim import ExternalGame, ExternalTeam
    from rll_bt.comm import layout
    from teamserver.status import load
    rll_bt = str(Path(sys.executable).parent / "rll-bt")
    helped = subprocess.run([rll_bt, "teamserver", "--help"], capture_output=True, text=True, timeout=120)
    assert helped.returncode == 0 and "--robots {rll-bt,agenttask}" in helped.stdout, helped.stdout
    off = free_port_offset()
    listen = free_ports(1, tcp=True)[0]
    state, err = tmp_path / "ts.sqlite", tmp_path / "ts.err"
    cmd = [rll_bt, "teamserver", "--profile", "rcll2025", "--team", TEAM, "--key", KEY, "--robots", "agenttask",
           "--listen", f"127.0.0.1:{listen}", "--refbox-host", "127.255.255.255", "--refbox-port-offset", str(off),
           "--state", str(state), "--heartbeat-timeout", "60"]     # (a loaded machine may stall this process)
    with open(err, "w") as fe:      # Ctrl-C as from a terminal (a test worker may ignore SIGINT, and so its children)
        ts = subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=fe,
                              preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    game = None
    try:
        game = ExternalGame([ExternalTeam("CYAN", ("127.0.0.1", listen), TEAM, KEY, robots=1)],
                            profile="rcll2025", seed=8, layout=layout("sim").moved(off),
                            phases={"setup": 3.0, "exploration": 600.0, "production": 1200.0}, speed=3.0)
        assert game.connect(timeout=60.0), err.read_text()       # (it retries until the server listens)
        agent = game.agents[("CYAN", 1)]

        def done(g):
            return any(r.successful for r in agent.finished.values())
        assert game.run_until(done, 240.0), (err.read_text()[-3000:], agent.finished)
        ids = [tid for tid, r in agent.finished.items() if r.successful]
        # the next task comes once the server has taken the result in
        assert game.run_until(lambda g: agent.book.current is not None and agent.book.current.task_id not in ids,
                              120.0), err.read_text()[-3000:]
        assert ts.poll() is None, err.read_text()[-3000:]
        ts.send_signal(signal.SIGINT)
        assert ts.wait(timeout=60.0) == 130, err.read_text()[-3000:]
    finally:
        if ts.poll() is None:
            ts.kill()
            ts.wait()
        if game is not None:
            game.close()
    text = err.read_text()
    assert f"listening on 127.0.0.1:{listen} for agenttask robots" in text and "interrupted" in text, text
    kb = load(str(state))
    try:
        assert sorted(kb.robots) == [1]
        done = [t for t in kb.tasks.values() if t.robot == 1 and t.state == "DONE"]
        assert done and {t.kind for t in done} == {"explore_zone"}, \
            [(t.kind, t.state, t.robot) for t in kb.tasks.values()]
    finally:
        kb.store.close()
