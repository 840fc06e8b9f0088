"""A whole game with every part in its own process, as in a real game.

    game = ProcessGame(GameOptions(seed=3, processes=True, out=Path("game")))
    result = game.run()                 # or run_until / run_for and faults in between
    game.close()

This process holds the world: PyBullet, the robots and the stations' physical state.  It serves each robot's
backend over TCP (the serving end of the ``remote`` backend, found through its entry point) and the stations
to the refbox over the simulator's station link (TCP too).  The simulated refbox is its own process (for
PyBullet ``rll-bt refbox sim --world remote:...``): it talks UDP (broadcast to ``127.255.255.255`` on free
local ports, split send/receive) and sees the stations only through the link. The team server runs as
``python -m games.child`` (TCP for the agents, UDP to the refbox) and each robot as a real ``rll-bt agent
--backend remote`` process.  Everything runs on the wall clock, at the world's pace (:mod:`.world_pace`).
The refbox's view
(status, points, awards, deliveries, station states) reaches this process through the snapshot file it
rewrites (``refbox.json``, 4 times a second), the team server's through ``teamserver.json`` (every second).

Two teams (``GameOptions(cyan=..., magenta=...)``): each of ours has its own team server process
(``teamserver-cyan``, ...: its files are named so) and agent processes (``agent-cyan1``, ...) on its own
team channel and key. An ``external`` team is another team's software: the refbox knows its name and key and
plays it on its channel; nothing of it runs here, and ``external-<colour>.json`` in the game's folder tells
it the refbox's UDP host, ports and its key (:meth:`ProcessGame.external`).  The refbox comes up first (the
recorder needs its light codes), then the rest.

The message log holds what the refbox sends and receives (logged by the refbox process) and every message of
the team server's link to the agents (logged by the team server process), both on the wall clock, mapped
onto the simulation clock and merged in time order at the end (:mod:`.teamlog`). Each robot's task intervals
(busy time, timeline) are read from those team messages.  Faults as in lockstep: :meth:`kill_agent`
(SIGKILL), :meth:`start_agent`, :meth:`restart_teamserver` (SIGKILL and a new process on the same database),
:meth:`restart_refbox` (SIGKILL and a new refbox process on the same ports), :meth:`station_down` (an operator
command to the refbox process over the station link).  Times given to
:meth:`run_for` and :meth:`run_until` are simulated seconds (about wall seconds).
"""
from __future__ import annotations

import json
import subprocess
import sys
import tempfile
from collections.abc import Callable
from pathlib import Path

from rll_bt import plugins
from rll_bt.backend import ENTRY_POINT_GROUP as BACKENDS
from rll_bt.comm import Layout, PeerPorts, free_ports
from rll_bt.contracts import load_simulator

from .lockstep import TEAM, GameResult, legacy_single
from .options import GameOptions
from .proccommands import CLI_MAIN, ChildExited, agent_command, teamserver_config
from .processlog import game_logs
from .recorder import Recorder
from .teamlog import WallToSim
from .teams import Team, joining
from .world_pace import world_advance

BROADCAST = "127.255.255.255"


class ProcessGame:
    """See the module doc.  ``clock`` must be the machine's monotonic wall
    clock (:class:`~rll_bt.clock.WallClock`): the team server's log is
    stamped with it in another process."""

    def __init__(self, options: GameOptions, *, progress=None, clock=None, connect_timeout: float | None = None):
        from rll_bt.clock import WallClock
        self.options = o = options
        self.wall = clock or WallClock()
        self.progress = progress
        # 60 s and 60 s per process to start (one team of three: 360 s; 160 s was too short at load 18-27)
        n = 1 + sum(1 + t.robots for t in o.lineup().values() if not t.external)
        self.connect_timeout = connect_timeout if connect_timeout is not None else 60.0 + 60.0 * n
        self._tmp = tempfile.TemporaryDirectory(prefix="rll-bt-game-")
        self.dir = Path(o.out) if o.out is not None else Path(self._tmp.name)
        self.dir.mkdir(parents=True, exist_ok=True)
        self.lineup = lineup = o.lineup()
        if "CYAN" not in lineup:
            raise ValueError("with --processes a team plays cyan: give --cyan")
        self.legacy = legacy_single(lineup)
        self.ours = {c: t for c, t in lineup.items() if not t.external}
        home = next(iter(self.ours.values()))
        self.sim = self._open_simulation()
        self.world, self.refbox = self.sim.world, self.sim.refbox
        self.clock = self.world.clock
        self.time_map = WallToSim()
        self.layout = self._refbox_layout()
        self.robots = list(range(1, home.robots + 1))      # the first team's, as in a game of one team
        self.backends = {(c, n): self.world.backend(c, n) for c, t in self.ours.items()
                         for n in range(1, t.robots + 1)}
        # the remote backend's serving end, found through its entry point like the agents' end
        self.server = plugins.load(BACKENDS, "remote").serve(
            lambda team, n: self.backends.get((str(team).upper(), int(n))), self.clock.now)
        self.snapshot_file = self.dir / f"{self._ts_name(home.color)}.json"
        self.refbox_file = self.dir / "refbox.json"
        self._refbox_log = self.dir / "refbox-messages.jsonl" if o.out is not None or o.record else None
        self._refbox_logs = [self._refbox_log] if self._refbox_log is not None else []    # one per refbox process
        self._snap: dict[str, dict] = {}
        self.procs: dict[str, subprocess.Popen] = {}
        self.recorders: dict[str, Recorder] = {}
        self._logs = []
        self._team_logs: dict[str, list[Path]] = {c: [] for c in self.ours}
        # (wall time, team, robot) of killed agents: on the clock the team server stamps its lines with,
        # so that a task sent just before the kill starts before it once both are mapped
        self._kills: list[tuple[float, str, int]] = []
        self._agent_starts = 0
        self.restarts: dict[str, int] = dict.fromkeys(self.ours, 0)
        self.refbox_restarts = 0
        self._t0 = 0.0                  # sim time the game started (the world runs while processes start)
        self._started = False
        self._result_made = False
        self.watch = None
        if o.record is not None:             # each process records its part, merged at the end (.procwatch)
            from .procwatch import ProcessWatch
            self.watch = ProcessWatch(self, o.record, self.dir / "recording")
        try:
            self._start_children()
        except BaseException:
            self.close()
            raise

    #: where the team server and the agents send to the refbox (it broadcasts back)
    refbox_host = BROADCAST

    def _open_simulation(self):
        """The world, and the simulated refbox to run as a process (for both teams when two play)."""
        o = self.options
        home = next(iter(self.ours.values()))
        teams = {} if self.legacy else {"teams": {c: (t.name, t.key) for c, t in self.lineup.items()}}
        return load_simulator(o.simulator)(
            profile=o.profile, seed=o.seed, team_name=home.name, key=home.key, perception=o.perception,
            gui=o.gui, phases=o.phases(), world_step=o.world_step, robot_options={"laser_rate": o.laser_rate},
            refbox="process", **o.stored(), **teams)

    def _refbox_layout(self) -> Layout:
        """The refbox's UDP ports (the refbox's view): free ones for the refbox process."""
        p = free_ports(6)
        return Layout("game", public=PeerPorts(send=p[0], recv=p[1]), cyan=PeerPorts(send=p[2], recv=p[3]),
                      magenta=PeerPorts(send=p[4], recv=p[5]), stream=-1)

    def _start_refbox(self) -> None:
        """The refbox process, up before anything else (the recorder needs its truth)."""
        self._spawn_refbox(self._refbox_log)
        self._wait_for(self.refbox.ready, "the refbox")

    def _spawn_refbox(self, message_log: Path | None) -> None:
        self._spawn("refbox", [sys.executable, "-c", CLI_MAIN, *self.refbox.command(
            host=BROADCAST, layout=self.layout, snapshot=self.refbox_file, message_log=message_log)])

    # -- names -----------------------------------------------------------------------------------
    def _ts_name(self, color: str) -> str:
        """The team server process of ``color`` (and the stem of its files)."""
        return "teamserver" if self.legacy else f"teamserver-{color.lower()}"

    def _agent_name(self, color: str, n: int) -> str:
        return f"agent{n}" if self.legacy else f"agent-{color.lower()}{n}"

    def _team(self, team: str | None) -> Team:
        if team is None:
            return next(iter(self.ours.values()))
        if team.upper() not in self.ours:
            raise ValueError(f"no team of ours plays {team} (ours: {', '.join(self.ours)})")
        return self.ours[team.upper()]

    @property
    def recorder(self) -> Recorder | None:
        """The first team's recorder (as in a game of one team)."""
        return next(iter(self.recorders.values()), None)

    def external(self, color: str) -> dict:
        """What the external team playing ``color`` needs to join (:func:`.teams.joining`)."""
        return joining(self.lineup[color.upper()], self.layout, BROADCAST)

    # -- children ----------------------------------------------------------------------------
    def _spawn(self, name: str, cmd: list[str]) -> None:
        log = open(self.dir / f"{name}.log", "a")  # noqa: SIM115 - closed with the game
        self._logs.append(log)
        self.procs[name] = subprocess.Popen(cmd, stdout=log, stderr=subprocess.STDOUT, stdin=subprocess.DEVNULL)

    def _start_children(self) -> None:
        """The refbox first (the recorder needs its truth), then the team server and the agents."""
        o = self.options
        self._ts_port = dict(zip(self.ours, free_ports(len(self.ours), tcp=True), strict=True))
        for old in [self.refbox_file, self.dir / "messages.jsonl", *self.dir.glob("refbox-messages*.jsonl"),
                    *self.dir.glob("teamserver*.sqlite*"), *self.dir.glob("teamserver*.json"),
                    *self.dir.glob("teamserver*-messages*.jsonl"), *self.dir.glob("external-*.json")]:
            old.unlink(missing_ok=True)
        for name in ("refbox", *(self._ts_name(c) for c in self.ours),
                     *(self._agent_name(c, n) for c, n in self.backends)):
            (self.dir / f"{name}.log").unlink(missing_ok=True)
        self._start_refbox()
        for c, t in self.lineup.items():
            robots = [] if t.external else list(range(1, t.robots + 1))
            self.recorders[c] = Recorder(self.world, self.refbox, c, robots, o.sample_period,
                                         snapshot=None if t.external else (lambda c=c: self.snapshot(c)))
            if t.external:
                (self.dir / f"external-{c.lower()}.json").write_text(json.dumps(self.external(c), indent=2))
        truth = {n: s.zone for n, s in self.refbox.stations().items()}
        self._ts_cfg = {}
        for c, t in self.ours.items():
            self._ts_cfg[c] = teamserver_config(o, t, self._ts_name(c), folder=self.dir, refbox_host=self.refbox_host,
                                                layout=self.layout, listen=self._ts_port[c], truth=truth,
                                                legacy=self.legacy)
            self._spawn_teamserver(c)
        for c, n in self.backends:
            self._spawn_agent(n, first_start=True, team=c)

    def _wait_for(self, ready: Callable[[], bool], what: str) -> None:
        """Until ``ready()`` (the world runs meanwhile); :class:`ChildExited` if a process ends or time runs out."""
        start = last = self.wall.now()
        while not ready():
            if self.wall.now() - start > self.connect_timeout:
                raise ChildExited(f"{what} did not come up in {self.connect_timeout:g} s; see the logs in {self.dir}")
            last = self._tick(last)
            self._check_children()

    def _spawn_teamserver(self, color: str) -> None:
        name = self._ts_name(color)
        logs = self._team_logs[color]
        k = len(logs)
        log = self.dir / (f"{name}-messages.jsonl" if k == 0 else f"{name}-messages-{k + 1}.jsonl")
        logs.append(log)
        cfg_file = self.dir / f"{name}-config.json"
        cfg_file.write_text(json.dumps({**self._ts_cfg[color], "message_log": str(log)}))
        self._spawn(name, [sys.executable, "-m", "games.child", str(cfg_file)])

    def _agent_backend_args(self, n: int, team: str = TEAM) -> list[str]:
        """The ``rll-bt agent`` arguments naming robot ``n``'s backend."""
        return ["--backend", "remote", "--backend-opt", f"address=127.0.0.1:{self.server.port}",
                "--backend-opt", f"robot={n}" if team == TEAM else f"robot={team}/{n}"]

    def _spawn_agent(self, n: int, first_start: bool, known_pose: bool = True, team: str | None = None) -> None:
        t = self._team(team)
        self._spawn(self._agent_name(t.color, n), agent_command(
            self.options, t, n, backend=self._agent_backend_args(n, t.color), teamserver_port=self._ts_port[t.color],
            refbox_host=self.refbox_host, layout=self.layout, first_start=first_start, legacy=self.legacy,
            pose=self.world.robot_pose(t.color, n) if known_pose else None,
            extra=self._net_args(n) + self._record_args(n)))

    def _net_args(self, n: int) -> list[str]:
        """The --net-* faults of robot ``n``'s agent (its seed: the game's and the agent start's)."""
        args = self.options.net.args(n)
        if args:
            self._agent_starts += 1
            args += ["--net-seed", f"{self.options.seed}/{self._agent_starts}"]
        return args

    def _record_args(self, n: int) -> list[str]:
        """``--record`` for an agent of a recorded game (a game of one team: ``GameOptions`` refuses two)."""
        if self.watch is None:
            return []
        cam = self.options.record_camera
        return ["--record", str(self.watch.agent_part(n))] + (["--record-camera", str(cam)] if cam > 0 else [])

    def _serve(self, timeout: float) -> None:
        """Answer the agents' backend calls (up to ``timeout`` s) and the refbox's station calls."""
        self.server.poll(timeout)
        self.refbox.step()

    def _kill(self, name: str) -> None:
        p = self.procs.pop(name, None)
        if p is not None and p.poll() is None:
            p.kill()
            while p.poll() is None:          # keep the backends and the stations answered meanwhile
                self._serve(0.01)

    # -- faults ------------------------------------------------------------------------------
    def kill_agent(self, number: int, team: str | None = None) -> None:
        """The agent process dies without a goodbye (SIGKILL): its links drop,
        its robot stops once the last drive command times out."""
        t = self._team(team)
        self._kill(self._agent_name(t.color, number))
        self._kills.append((self.wall.now(), t.color, number))
        self.recorders[t.color].note("agent killed", robot=number)

    def start_agent(self, number: int, known_pose: bool = True, team: str | None = None) -> None:
        """A new agent process for robot ``number`` (no memory of earlier tasks),
        starting from the robot's true pose, as an operator would set it, or
        with ``known_pose=False`` finding it by global localisation."""
        t = self._team(team)
        if self._agent_name(t.color, number) in self._alive():
            raise RuntimeError(f"the agent of robot {number} is running")
        self._spawn_agent(number, first_start=False, known_pose=known_pose, team=t.color)
        self.recorders[t.color].note("agent started", robot=number)

    def restart_teamserver(self, team: str | None = None, between: Callable[[], None] | None = None) -> None:
        """Kill the team server process (SIGKILL) and start a new one on the
        same database and agent port; the agents reconnect to it.  ``between()``
        runs when the old process is gone and the new one not yet started."""
        t = self._team(team)
        self._kill(self._ts_name(t.color))
        self.restarts[t.color] += 1
        if between is not None:
            between()
        self._spawn_teamserver(t.color)
        self.recorders[t.color].note("team server restarted")

    def restart_refbox(self) -> None:
        """Kill the refbox process (SIGKILL) and start a new one on the same ports (a crash of its machine): it
        keeps no state, so its game starts afresh, at once; the team servers and agents hear it again."""
        self._kill("refbox")
        self.refbox_restarts += 1
        self.refbox_file.unlink(missing_ok=True)
        if self._refbox_logs:          # a message log of its own, merged with the others at the end
            self._refbox_logs.append(self.dir / f"refbox-messages-{len(self._refbox_logs) + 1}.jsonl")
        self._spawn_refbox(self._refbox_logs[-1] if self._refbox_logs else None)
        self._wait_for(lambda: self.refbox.ready() and self._start_game(), "the restarted refbox")
        for rec in self.recorders.values():
            rec.note("refbox restarted")

    def _start_game(self) -> bool:
        """The start command to the refbox process; False while its station link is not up."""
        try:
            return self.refbox.start() is None
        except RuntimeError:
            return False

    def station_down(self, machine: str, seconds: float) -> None:
        self.refbox.station_down(machine, seconds)
        for rec in self.recorders.values():
            rec.note("station down", machine=machine, seconds=seconds)

    def snapshot(self, team: str | None = None) -> dict:
        """A team server's view as it last wrote it (``now``: its wall clock);
        ``team``: its colour (default the first team of ours)."""
        color = self._team(team).color
        try:
            self._snap[color] = json.loads((self.dir / f"{self._ts_name(color)}.json").read_text())
        except (OSError, ValueError):
            pass
        return self._snap.get(color, {})

    def _dead(self) -> list[str]:
        """The parts without which the game cannot go on that are gone."""
        return [name for name in ("refbox", *(self._ts_name(c) for c in self.ours)) if name not in self._alive()]

    def _alive(self) -> list[str]:
        return [name for name, p in self.procs.items() if p.poll() is None]

    # -- running ---------------------------------------------------------------------------------
    catch_up: float | None = None     #: how far behind the world may fall and still step it all (world_pace)

    def _tick(self, last: float) -> float:
        """Serve backend and station calls for a moment, then advance the world by the wall time passed;
        the wall time the world stands at."""
        self._serve(0.005)
        now = self.wall.now()
        dt, stepped_to = world_advance(last, now, 0.1, self.catch_up)
        if dt >= self.options.world_step * 0.5:
            self.world.step(dt)
            self.time_map.add(now, self.clock.now())
            if self.watch is not None:
                self.watch.stepped()
            self.refbox.step()
            if self._started:
                before = len(self.recorder.rec.samples)
                for rec in self.recorders.values():
                    rec.sample()
                if self.progress is not None and len(self.recorder.rec.samples) != before:
                    self.progress(self.clock.now() - self._t0, self.refbox.status())
            elif self.progress is not None:       # the processes are coming up (the bar throttles itself)
                self.progress(0.0, self.refbox.status())
            return stepped_to
        return last

    def _wait_for_robots(self) -> bool:
        """Until the team server has every robot (the world runs meanwhile, the game does not)."""
        def ready() -> bool:
            return all(self.snapshot(c).get("robots", {}).get(str(n), {}).get("status") == "ACTIVE"
                       for c, n in self.backends)
        try:
            self._wait_for(ready, "the team server's robots")
        except ChildExited:
            return False
        return True

    def start(self) -> bool:
        """Wait for every process to come up, then start the game; whether they came up."""
        if self._started:
            return True
        if not self._wait_for_robots():
            self.recorder.note("not every process came up", alive=self._alive())
            print(f"rll-bt sim: not every robot was ACTIVE at the team server within {self.connect_timeout:g} s "
                  f"(alive: {', '.join(self._alive()) or 'none'}; see the logs in {self.dir})", file=sys.stderr)
            return False
        self._started = True
        self.refbox.start()
        self._t0 = self.clock.now()
        self._last = self._wall0 = self.wall.now()
        for rec in self.recorders.values():
            rec.sample(force=True)
        return True

    def run_until(self, predicate: Callable[[ProcessGame], bool], limit: float) -> bool:
        """Run until ``predicate(game)`` or ``limit`` more simulated seconds; whether it held.
        :class:`ChildExited` if a process ended that no fault method stopped."""
        if not self.start():
            raise ChildExited(f"not every process came up (alive: {', '.join(self._alive()) or 'none'}; "
                              f"see the logs in {self.dir})")
        end = self.clock.now() + limit
        while self.clock.now() < end:
            if predicate(self):
                return True
            self._last = self._tick(self._last)
            self._check_children()
        return predicate(self)

    def _check_children(self) -> None:
        for name, p in self.procs.items():
            if p.poll() is not None:
                raise ChildExited(f"the {name} process exited ({p.returncode}); see {self.dir / (name + '.log')}")

    def run_for(self, seconds: float) -> None:
        self.run_until(lambda g: False, seconds)

    def finished(self) -> bool:
        return self.options.game_over(self.refbox.status())

    def run(self, limit: float | None = None) -> GameResult:
        """Play until the game is over, at most ``limit`` simulated seconds
        (default: the expected length plus overtime and a margin)."""
        if not self.start():
            return self.result(False)
        o = self.options
        if limit is None:
            limit = o.expected_duration() + o.overtime_length() + 60.0
        end = self.clock.now() + limit
        while self.clock.now() < end and not self.finished():
            dead = self._dead()
            if dead:
                self.recorder.note(f"the {dead[0]} process died", log=str(self.dir / f"{dead[0]}.log"))
                break
            self._last = self._tick(self._last)
        return self.result(self.finished())

    def result(self, finished: bool) -> GameResult:
        """The game as lockstep reports it (simulated seconds since the game started)."""
        if self._result_made:
            raise RuntimeError("the result of this game was already made")
        self._result_made = True
        if self._started:
            for r in self.recorders.values():
                r.sample(force=True)
            lag = (self.wall.now() - self._wall0) - (self.clock.now() - self._t0)
            if lag > 1.0:         # the agents' timeouts ran on the wall clock meanwhile
                self.recorder.note("the world fell behind the wall clock", seconds=round(lag, 1))
        self._stop_children()
        snaps = {}
        for c in self.ours:
            snaps[c] = dict(self.snapshot(c))
            snaps[c]["restarts"] = self.restarts[c]
        t0, end = self._t0, self.clock.now()
        kills = [(round(self.time_map(w), 4) if len(self.time_map) else end, c, n) for w, c, n in self._kills]
        channels = {c: "teamserver" if self.legacy else self._ts_name(c) for c in self.ours}
        names = {c.lower(): self._ts_name(c) if c in self.ours else f"external-{c.lower()}" for c in self.lineup}
        messages = game_logs(self.dir, self._refbox_logs if self._refbox_log else [], self._team_logs, self.time_map,
                             t0=t0, end=end, recordings={c: r.rec for c, r in self.recorders.items()},
                             channels=channels, kills=kills, servers=None if self.legacy else names)
        collisions = self.world.collision_log()
        home = next(iter(self.ours))
        result = GameResult(finished=finished, status=self.refbox.status(), recording=self.recorder.rec,
                            awards=self.refbox.awards(), deliveries=self.refbox.deliveries(), snapshot=snaps[home],
                            stations=self.refbox.stations(), orders=self.refbox.orders(), collisions=len(collisions),
                            sim_time=end - t0, messages=messages, tally={c: self.refbox.tally(c) for c in self.ours},
                            collision_log=[(round(t - t0, 3), *rest) for t, *rest in collisions],
                            recordings={c: r.rec for c, r in self.recorders.items()}, snapshots=snaps,
                            labels={c: t.label for c, t in self.lineup.items()},
                            sightings=self.world.laser_sightings())
        if self.watch is not None:
            self.watch.finish(result, self.dir / "messages.jsonl", t0)
        return result

    def _stop_children(self, timeout: float = 10.0) -> None:
        """SIGTERM to every child; keep serving the backends while they stop their robots."""
        for p in self.procs.values():
            if p.poll() is None:
                p.terminate()
        start = self.wall.now()
        while self._alive() and self.wall.now() - start < timeout:
            self._serve(0.01)
        for p in self.procs.values():
            if p.poll() is None:
                p.kill()
                p.wait()

    def close(self) -> None:
        self._stop_children()
        if self.watch is not None:
            self.watch.watch.close()
        for log in self._logs:
            log.close()
        self.server.close()
        self.sim.close()
        self._tmp.cleanup()

    def __enter__(self) -> ProcessGame:
        return self

    def __exit__(self, *exc) -> None:
        self.close()
