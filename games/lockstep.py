"""A whole game in one process on one simulated clock.

    game = LockstepGame(GameOptions(seed=3))
    result = game.run()                  # GameResult: finished, status, recording, ...

Every round: each agent steps (polls its links, ticks its tree when due,
sends what is due), the world advances ``dt``, the refbox receives, ticks
and sends, the team server ticks, the recorder samples.  All messages pass
the in-process :class:`~rll_bt.comm.Bus` as encoded frames (the team
channel and the team-server link encrypted with the team key), so the same
bytes as in a real game; a seeded game is deterministic.

The simulator and the team server come from the ``rll_bt.simulators`` and
``rll_bt.teamservers`` entry points (:mod:`rll_bt.contracts`): ``game.world``
is the simulator's :class:`~rll_bt.contracts.World`, ``game.refbox`` its
refbox (an :class:`~rll_bt.contracts.InProcessRefbox`, whose
:class:`~rll_bt.contracts.RefboxView` tells the game's state).  Faults for tests
and demonstrations: :meth:`kill_agent`, :meth:`start_agent`,
:meth:`restart_teamserver`, :meth:`station_down`.
"""
from __future__ import annotations

import tempfile
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

from rll_bt import msgs
from rll_bt.agent import AgentConfig, RobotAgent
from rll_bt.comm import Bus, MessageRegistry
from rll_bt.comm.msglog import MessageLog
from rll_bt.contracts import GameStatus, TeamServerOptions, load_simulator, load_teamserver

from .options import GameOptions
from .recorder import Recorder, Recording

TEAM = "CYAN"


@dataclass
class GameResult:
    finished: bool               # the game reached its end (or the end of exploration with until=exploration)
    status: GameStatus
    recording: Recording
    awards: list
    deliveries: list
    snapshot: dict
    stations: dict
    orders: list
    collisions: int
    sim_time: float
    collision_log: list = field(default_factory=list)
    wall_time: float = 0.0
    messages: int = 0
    tally: dict = field(default_factory=dict)    # team -> rll_bt.contracts.Tally


class LockstepGame:
    """See the module doc.  ``progress``: called with (sim time, status) after
    each sample; ``hooks``: callables ``hook(game)`` run after every round."""

    def __init__(self, options: GameOptions, *, progress: Callable | None = None, pace=None):
        self.options = o = options
        self.pace = pace              # a wall Clock: keep to ``options.pace`` (real time: 1); None: as fast as possible
        sim_factory = load_simulator(o.simulator)
        ts_factory = load_teamserver(o.teamserver)
        self.sim = sim_factory(profile=o.profile, seed=o.seed, team_name=o.team_name, key=o.key,
                               perception=o.perception, gui=o.gui, phases=o.phases(),
                               world_step=o.world_step, robot_options={"laser_rate": o.laser_rate},
                               refbox="here", **o.stored())
        self.world, self.refbox = self.sim.world, self.sim.refbox
        try:
            self._wire(o, ts_factory)
        except BaseException:
            if getattr(self, "watch", None) is not None:
                self.watch.close()
            self.sim.close()
            raise
        self.progress = progress
        self.hooks: list[Callable] = []
        self.rounds = 0
        self._started = False

    def _wire(self, o: GameOptions, ts_factory) -> None:
        """Bus, message log, team server, agents and recorder around the simulation."""
        self.clock = self.world.clock
        self.bus = Bus(self.clock)
        self.ref_reg = MessageRegistry.from_message_set(msgs.message_set(self.world.profile.name))
        self.team_reg = MessageRegistry.from_message_set(msgs.message_set("team"))
        self.log: MessageLog | None = None
        if o.out is not None:
            o.out.mkdir(parents=True, exist_ok=True)
            self.log = MessageLog(o.out / "messages.jsonl", self.clock,
                                  {"teamserver": self.team_reg}, self.ref_reg, key=o.key)
            self.bus.tap(self.log.tap)
        self.watch = self.view = None
        if o.record is not None or o.live is not None or o.view is not None:
            from .watch import GameWatch
            self.watch = GameWatch(self, o)
        if o.view is not None:
            from .view import attach
            self.view = attach(self.watch.watch, port=o.view, profile=o.profile,
                               meta={"kind": "sim", "name": f"rll-bt sim --seed {o.seed}", "seed": o.seed})
        self.refbox.attach_bus(self.bus)
        self._tmp = None
        state = o.state
        if state is None:
            if o.out is not None:
                state = o.out / "teamserver.sqlite"
                if state.exists():
                    state.unlink()
            else:
                self._tmp = tempfile.TemporaryDirectory(prefix="rll-bt-sim-")
                state = Path(self._tmp.name) / "teamserver.sqlite"
        truth = ({n: s.zone for n, s in self.refbox.stations().items()}
                 if o.strategy == "oracle" else None)
        bus, reg, key = self.bus, self.ref_reg, o.key
        self.teamserver = ts_factory(
            profile=o.profile, team_name=o.team_name, key=key, clock=self.clock,
            refbox_public=lambda: bus.peer("public", registry=reg, name="teamserver"),
            refbox_team=lambda color: bus.peer(color.lower(), registry=reg, name="teamserver"),
            agents=lambda: bus.stream_server("teamserver", registry=self.team_reg, key=key),
            state=str(state), strategy=o.strategy, seed=o.seed, oracle=truth,
            options=TeamServerOptions(baseline=o.baseline, map_period=o.map_period, extra=o.extra))
        self.agents: dict[int, RobotAgent] = {}
        self.robot_numbers = list(range(1, o.robots + 1))
        for n in self.robot_numbers:
            self.start_agent(n, restarted=False)
        self.recorder = Recorder(self.world, self.refbox, TEAM, self.robot_numbers, o.sample_period,
                                 snapshot=self.teamserver.snapshot)
        if self.watch is not None:
            self.recorder.listeners.append(self.watch.recorded)

    # -- parts -------------------------------------------------------------------------
    def start_agent(self, number: int, restarted: bool = True, known_pose: bool = True) -> RobotAgent:
        """A new agent for robot ``number`` (its robot stays where it is; the
        agent starts from the robot's true pose, as an operator would set it,
        or with ``known_pose=False`` finds it by global localisation)."""
        o, bus, reg = self.options, self.bus, self.ref_reg
        name = f"R{number}"
        cfg = AgentConfig(robot_id=number, team_name=o.team_name, profile=o.profile, hz=o.hz)
        backend = self.world.backend(TEAM, number)
        rw = self.watch.robot(number) if self.watch is not None else None
        agent = RobotAgent(
            cfg, clock=self.clock, backend=backend if rw is None else rw.tap(backend),
            link=bus.stream_client("teamserver", registry=self.team_reg, key=o.key, name=name),
            public=bus.peer("public", registry=reg, name=name),
            team=lambda color: bus.peer(color.lower(), registry=reg, key=o.key, name=name),
            services={"localisation": o.localisation},
            start_pose=self.world.robot_pose(TEAM, number) if known_pose else None, restarted=restarted)
        self.agents[number] = agent
        if rw is not None:
            rw.attach(agent)
        if restarted:
            self._note("agent started", robot=number)
        return agent

    def kill_agent(self, number: int) -> None:
        """The agent dies without a goodbye: its links drop, its robot stops
        once the last drive command times out."""
        agent = self.agents.pop(number)
        self.recorder.task(number, None, outcome="agent killed")
        agent.link.close()
        agent.refbox.close()
        self._note("agent killed", robot=number)

    def restart_teamserver(self) -> None:
        self.teamserver.restart()
        self._note("team server restarted")

    def station_down(self, machine: str, seconds: float) -> None:
        self.refbox.station_down(machine, seconds)
        self._note("station down", machine=machine, seconds=seconds)

    def _note(self, what: str, **data) -> None:
        if hasattr(self, "recorder"):
            self.recorder.note(what, **data)

    # -- running -------------------------------------------------------------------------
    def start(self) -> None:
        if not self._started:
            self._started = True
            self.refbox.start()
            if self.watch is not None:
                self.watch.stations()
            self.recorder.sample(force=True)

    def round(self) -> None:
        """One lockstep round of ``dt`` seconds."""
        for n in sorted(self.agents):
            agent = self.agents[n]
            before = agent.run
            agent.step()
            run = agent.run
            ended = before.outcome.status if before is not None and before.done else None
            if run is not None and not run.done:
                self.recorder.task(n, run.kind, run.task_id, outcome=ended)
            else:
                self.recorder.task(n, None, outcome=ended)
        self.world.step(self.options.dt)
        self.refbox.step()
        self.teamserver.tick()
        self.rounds += 1
        if self.watch is not None:
            self.watch.round()
        if self.pace is not None:
            self._keep_real_time()
        before = len(self.recorder.rec.samples)
        self.recorder.sample()
        if self.progress is not None and len(self.recorder.rec.samples) != before:
            self.progress(self.clock.now(), self.refbox.status())
        for hook in list(self.hooks):
            hook(self)

    def _keep_real_time(self) -> None:
        if not hasattr(self, "_pace0"):
            self._pace0 = (self.pace.now(), self.clock.now())
        wall0, sim0 = self._pace0
        speed = self.options.pace or 1.0
        ahead = (self.clock.now() - sim0) / speed - (self.pace.now() - wall0)
        if ahead > 0:
            self.pace.sleep(ahead)

    def finished(self) -> bool:
        return self.options.game_over(self.refbox.status())

    def exploration_over(self, st: GameStatus | None = None) -> bool:
        return self.options.exploration_over(st or self.refbox.status())

    def run_for(self, seconds: float) -> None:
        self.start()
        end = self.clock.now() + seconds
        while self.clock.now() < end - 1e-9:
            self.round()

    def run_until(self, predicate: Callable[[LockstepGame], bool], limit: float) -> bool:
        """Run until ``predicate(game)`` or ``limit`` more simulated seconds; whether it held."""
        self.start()
        end = self.clock.now() + limit
        while self.clock.now() < end:
            if predicate(self):
                return True
            self.round()
        return predicate(self)

    def run(self, limit: float | None = None, stop: Callable[[LockstepGame], bool] | None = None) -> GameResult:
        """Play until the game is over (or ``stop(game)``), at most ``limit``
        simulated seconds (default: the expected length plus overtime and a margin)."""
        self.start()
        if limit is None:
            limit = self.options.expected_duration() + self.options.rules.phases.overtime + 60.0
        end = self.clock.now() + limit
        done = False
        while self.clock.now() < end:
            if self.finished() or (stop is not None and stop(self)):
                done = True
                break
            self.round()
        done = done or self.finished()
        self.recorder.sample(force=True)
        self.recorder.close_tasks()
        result = self.result(done)
        if self.watch is not None:
            self.watch.result(result)
        return result

    def result(self, finished: bool) -> GameResult:
        collisions = self.world.collision_log()
        return GameResult(finished=finished, status=self.refbox.status(), recording=self.recorder.rec,
                          awards=self.refbox.awards(), deliveries=self.refbox.deliveries(),
                          snapshot=self.teamserver.snapshot(), stations=self.refbox.stations(),
                          orders=self.refbox.orders(), collisions=len(collisions),
                          tally={TEAM: self.refbox.tally(TEAM)},
                          sim_time=self.clock.now(), messages=self.bus.frames,
                          collision_log=collisions)

    def close(self) -> None:
        for agent in self.agents.values():
            try:
                agent.shutdown()
            except Exception:
                pass
        self.teamserver.close()
        if self.log is not None:
            self.log.close()
        if self.view is not None:
            self.view.close()
        if self.watch is not None:
            self.watch.close()
        self.sim.close()
        if self._tmp is not None:
            self._tmp.cleanup()

    def __enter__(self) -> LockstepGame:
        return self

    def __exit__(self, *exc) -> None:
        self.close()
