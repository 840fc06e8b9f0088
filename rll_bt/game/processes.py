"""A whole game with every part in its own process, as in a real game.

This process holds the world and the simulated refbox: the refbox talks UDP
(broadcast to ``127.255.255.255`` on free local ports, the ``sim`` style of
split send/receive ports), and the world serves each robot's backend over
TCP (:mod:`.remote`).  The team server runs as ``python -m
rll_bt.game.child`` (TCP for the agents, UDP to the refbox) and each robot
as a real ``rll-bt agent --backend remote`` process.  Everything runs on the
wall clock: the world advances by the wall time that passed, so a game takes
its real length.  The team server's view reaches this process through the
snapshot file it rewrites every second.

The message log holds what the refbox sends and receives (the team
server's link to the agents crosses sockets between other processes and is
not logged; the lockstep mode logs every frame).  No faults on command.
"""
from __future__ import annotations

import json
import subprocess
import sys
import tempfile
from pathlib import Path

from ..comm import Layout, PeerPorts
from .interfaces import load_simulator
from .lockstep import TEAM, GameResult
from .options import GameOptions
from .recorder import Recorder
from .remote import BackendServer, free_ports

BROADCAST = "127.255.255.255"
AGENT_MAIN = "import sys; from rll_bt.cli import main; sys.exit(main())"


class ProcessGame:
    def __init__(self, options: GameOptions, *, progress=None, clock=None, connect_timeout: float = 60.0):
        from ..clock import WallClock
        self.options = o = options
        self.wall = clock or WallClock()
        self.progress = progress
        self.connect_timeout = connect_timeout
        self._tmp = tempfile.TemporaryDirectory(prefix="rll-bt-game-")
        self.dir = Path(o.out) if o.out is not None else Path(self._tmp.name)
        self.dir.mkdir(parents=True, exist_ok=True)
        self.sim = load_simulator(o.simulator)(
            profile=o.profile, seed=o.seed, team_name=o.team_name, key=o.key, perception=o.perception,
            gui=o.gui, phases=o.phases(), world_step=o.world_step, robot_options={"laser_rate": o.laser_rate})
        self.clock = self.sim.clock
        p = free_ports(6)
        self.layout = Layout("game", public=PeerPorts(send=p[0], recv=p[1]), cyan=PeerPorts(send=p[2], recv=p[3]),
                             magenta=PeerPorts(send=p[4], recv=p[5]), stream=-1)
        self.sim.attach_udp(BROADCAST, self.layout)
        self.log = None
        if o.out is not None:
            from .msglog import MessageLog
            self.log = MessageLog(self.dir / "messages.jsonl", self.clock, {}, self.sim.refbox_registry(), key=o.key)
            self.sim.tap(self.log.record)
        self.robots = list(range(1, o.robots + 1))
        self.backends = {n: self.sim.backend(TEAM, n) for n in self.robots}
        self.server = BackendServer(lambda team, n: self.backends[int(n)] if team == TEAM else None,
                                    self.clock.now)
        self.snapshot_file = self.dir / "teamserver.json"
        self._snap: dict = {}
        self.procs: dict[str, subprocess.Popen] = {}
        self.recorder = Recorder(self.sim, TEAM, self.robots, o.sample_period, snapshot=self.snapshot)
        self._logs = []
        self._t0 = 0.0                  # sim time the game started (the world runs while processes start)
        self._start_children()

    # -- children ----------------------------------------------------------------------------
    def _spawn(self, name: str, cmd: list[str]) -> None:
        log = open(self.dir / f"{name}.log", "w")
        self._logs.append(log)
        self.procs[name] = subprocess.Popen(cmd, stdout=log, stderr=subprocess.STDOUT, stdin=subprocess.DEVNULL)

    def _start_children(self) -> None:
        o = self.options
        ts_port = free_ports(1, tcp=True)[0]
        robot = {ch: (self.layout.robot(ch).send, self.layout.robot(ch).recv) for ch in ("public", "cyan", "magenta")}
        state = self.dir / "teamserver.sqlite"
        if state.exists():
            state.unlink()
        cfg = {"profile": o.profile, "team": o.team_name, "key": o.key, "refbox_host": BROADCAST,
               "ports": {ch: [robot[ch][0], robot[ch][1]] for ch in robot}, "listen": ts_port,
               "state": str(state), "strategy": o.strategy, "seed": o.seed, "baseline": o.baseline,
               "map_period": o.map_period, "snapshot": str(self.snapshot_file), "teamserver": o.teamserver,
               "oracle": ({n: s.zone for n, s in self.sim.stations().items()} if o.strategy == "oracle" else None)}
        cfg_file = self.dir / "teamserver-config.json"
        cfg_file.write_text(json.dumps(cfg))
        self._spawn("teamserver", [sys.executable, "-m", "rll_bt.game.child", str(cfg_file)])
        pub, team = self.layout.robot("public"), self.layout.robot("cyan")
        for n in self.robots:
            pose = self.sim.robot_pose(TEAM, n)
            self._spawn(f"agent{n}", [
                sys.executable, "-c", AGENT_MAIN, "agent", "--robot", str(n), "--team", o.team_name,
                "--key", o.key, "--profile", o.profile, "--backend", "remote",
                "--backend-opt", f"address=127.0.0.1:{self.server.port}", "--backend-opt", f"robot={n}",
                "--teamserver", f"127.0.0.1:{ts_port}", "--refbox-host", BROADCAST, "--layout", "sim",
                "--public-recv", str(pub.recv), "--public-send", str(pub.send),
                "--team-recv", str(team.recv), "--team-send", str(team.send),
                "--start-pose", f"{pose.x},{pose.y},{pose.theta}", "--hz", str(o.hz), "--first-start", "-q"])

    def snapshot(self) -> dict:
        try:
            self._snap = json.loads(self.snapshot_file.read_text())
        except (OSError, ValueError):
            pass
        return self._snap

    def _alive(self) -> list[str]:
        return [name for name, p in self.procs.items() if p.poll() is None]

    # -- running ---------------------------------------------------------------------------------
    def _tick(self, last: float) -> float:
        """Serve backend calls for a moment, then advance the world by the wall time passed."""
        self.server.poll(0.005)
        now = self.wall.now()
        dt = min(now - last, 0.1)
        if dt >= self.options.world_step * 0.5:
            self.sim.step(dt)
            self.sim.refbox_step()
            before = len(self.recorder.rec.samples)
            self.recorder.sample()
            if self.progress is not None and len(self.recorder.rec.samples) != before:
                self.progress(self.clock.now() - self._t0, self.sim.status())
            return now
        return last

    def _wait_for_robots(self) -> bool:
        """Until the team server has every robot (the world runs meanwhile, the game does not)."""
        start = last = self.wall.now()
        while self.wall.now() - start < self.connect_timeout:
            last = self._tick(last)
            robots = self.snapshot().get("robots", {})
            if all(robots.get(str(n), {}).get("status") == "ACTIVE" for n in self.robots):
                return True
            if len(self._alive()) < len(self.procs):
                return False
        return False

    def run(self) -> GameResult:
        ready = self._wait_for_robots()
        if not ready:
            self.recorder.note("not every process came up", alive=self._alive())
            return self._result(False)
        self.sim.start()
        t0_sim, t0_wall = self.clock.now(), self.wall.now()
        self._t0 = t0_sim
        self._offset = t0_wall - t0_sim
        o = self.options
        limit = o.expected_duration() + o.rules.phases.overtime + 60.0
        last = self.wall.now()
        finished = False
        while self.clock.now() - t0_sim < limit:
            last = self._tick(last)
            st = self.sim.status()
            if st.phase == "POST_GAME" or (o.until == "exploration" and self._exploration_over(st)):
                finished = True
                break
            if "teamserver" not in self._alive():
                self.recorder.note("the team server process died")
                break
        self.recorder.sample(force=True)
        return self._result(finished)

    def _exploration_over(self, st) -> bool:
        o = self.options
        if o.rules.phases.exploration_in_production > 0:
            return st.phase == "PRODUCTION" and st.game_time >= o.exploration_window()
        return st.phase in ("PRODUCTION", "POST_GAME")

    def _result(self, finished: bool) -> GameResult:
        self._stop_children()
        snap = self.snapshot()
        offset = getattr(self, "_offset", 0.0)
        rec = self.recorder.rec
        for t in snap.get("tasks", []):
            if t.get("robot") is None or t.get("assigned_at") is None:
                continue
            end = t.get("finished_at")
            rec.tasks.setdefault(int(t["robot"]), []).append(
                {"kind": t["kind"], "id": t["id"], "start": round(t["assigned_at"] - offset, 3),
                 "end": round(end - offset, 3) if end is not None else None,
                 "outcome": {"DONE": "SUCCEEDED", "FAILED": "FAILED"}.get(t["state"], t["state"])})
        for runs in rec.tasks.values():
            runs.sort(key=lambda r: r["start"])
            for run, nxt in zip(runs, runs[1:]):      # cancelled without an end: until the next one
                if run["end"] is None or run["end"] > nxt["start"]:
                    run["end"] = nxt["start"]
        return GameResult(finished=finished, status=self.sim.status(), recording=rec, awards=self.sim.awards(),
                          deliveries=self.sim.deliveries(), snapshot=snap, stations=self.sim.stations(),
                          orders=self.sim.orders(), collisions=self.sim.collisions(),
                          sim_time=self.clock.now(), messages=self.log.lines if self.log else 0,
                          collision_log=self.sim.collision_log())

    def _stop_children(self, timeout: float = 10.0) -> None:
        """SIGTERM to every child; keep serving the backends while they stop their robots."""
        for p in self.procs.values():
            if p.poll() is None:
                p.terminate()
        start = self.wall.now()
        while self._alive() and self.wall.now() - start < timeout:
            self.server.poll(0.01)
        for p in self.procs.values():
            if p.poll() is None:
                p.kill()
                p.wait()

    def close(self) -> None:
        self._stop_children()
        for log in self._logs:
            log.close()
        self.server.close()
        if self.log is not None:
            self.log.close()
        self.sim.close()
        self._tmp.cleanup()
