"""A whole game in one process on one simulated clock.

    game = LockstepGame(GameOptions(seed=3))
    result = game.run()                  # GameResult: finished, status, recording, ...

Every round: each agent steps (polls its links, ticks its tree when due,
sends what is due), the world advances ``dt``, the refbox receives, ticks
and sends, the team server ticks, the recorder samples.  All messages pass
the in-process :class:`~rll_bt.comm.Bus` as encoded frames (the team
channel and the team-server link encrypted with the team key), so the same
bytes as in a real game; a seeded game is deterministic.

Two teams (``GameOptions(cyan=..., magenta=...)``, :mod:`.teams`): each
colour is a :class:`Side` with its own team server (on its own bus stream,
``teamserver-cyan``/``teamserver-magenta``), agents and recorder, its own
team channel and key; a team knows only its own robots, the other team's
it meets only in its lasers.  ``game.teamserver``, ``game.agents``,
``game.robot_numbers`` and ``game.recorder`` are the first side's (cyan's
when it plays); ``game.sides`` holds both.

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
from rll_bt.agenttask import link as agent_link
from rll_bt.comm import Bus, MessageRegistry
from rll_bt.comm.faults import FaultyTransport
from rll_bt.comm.msglog import MessageLog
from rll_bt.contracts import GameStatus, TeamServerOptions, load_simulator, load_teamserver

from .options import GameOptions
from .recorder import Recorder, Recording
from .teams import Team

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
    #: per team colour: its recording and its team server's snapshot (``recording``/``snapshot``
    #: are the first team's); labels: colour -> the CONFIG it played (:mod:`.teams`)
    recordings: dict = field(default_factory=dict)
    snapshots: dict = field(default_factory=dict)
    labels: dict = field(default_factory=dict)
    sightings: dict = field(default_factory=dict)    # robot -> {robot of the other team: laser scans seeing it}


@dataclass
class Side:
    """One team of a game: its :class:`~.teams.Team`, the bus stream its team
    server serves (``stream``), the team server, its agents and its recorder."""

    team: Team
    stream: str
    teamserver: object = None
    agents: dict = field(default_factory=dict)
    recorder: Recorder | None = None

    @property
    def color(self) -> str:
        return self.team.color

    @property
    def robot_numbers(self) -> list[int]:
        return list(range(1, self.team.robots + 1))


def legacy_single(lineup: dict) -> bool:
    """One team of ours playing cyan with the options' own settings: the
    names on the bus are those of every game before two teams (``teamserver``,
    ``R1``), so such a game sends exactly the messages it always did."""
    return list(lineup) == ["CYAN"] and lineup["CYAN"].spec is None


class LockstepGame:
    """See the module doc.  ``progress``: called with (sim time, status) after
    each sample; ``hooks``: callables ``hook(game)`` run after every round."""

    def __init__(self, options: GameOptions, *, progress: Callable | None = None, pace=None):
        self._links_made = 0
        self.options = o = options
        self.pace = pace              # a wall Clock: keep to ``options.pace`` (real time: 1); None: as fast as possible
        lineup = o.lineup()
        if any(t.external for t in lineup.values()):
            raise ValueError("an external team plays over the network: give --processes")
        self.legacy = legacy_single(lineup)
        home = next(iter(lineup.values()))
        teams = {} if self.legacy else {"teams": {c: (t.name, t.key) for c, t in lineup.items()}}
        self.sides: dict[str, Side] = {
            c: Side(t, "teamserver" if self.legacy else f"teamserver-{c.lower()}") for c, t in lineup.items()}
        self.sim = load_simulator(o.simulator)(
            profile=o.profile, seed=o.seed, team_name=home.name, key=home.key, perception=o.perception, gui=o.gui,
            phases=o.phases(), world_step=o.world_step, robot_options={"laser_rate": o.laser_rate},
            refbox="here", **o.stored(), **teams)
        self.world, self.refbox = self.sim.world, self.sim.refbox
        try:
            self._wire(o)
        except BaseException:
            if getattr(self, "watch", None) is not None:
                self.watch.close()
            self.sim.close()
            raise
        self.progress = progress
        self.hooks: list[Callable] = []
        self.rounds = 0
        self._started = False

    def _wire(self, o: GameOptions) -> None:
        """Bus, message log, team servers, agents and recorders around the simulation."""
        self.clock = self.world.clock
        self.bus = Bus(self.clock)
        self.ref_reg = MessageRegistry.from_message_set(msgs.message_set(self.world.profile.name))
        self.team_reg = agent_link.registry()
        self.log: MessageLog | None = None
        if o.out is not None:
            o.out.mkdir(parents=True, exist_ok=True)
            keys = {a: sd.team.key for sd in self.sides.values() for a in (sd.color.lower(), sd.stream)}
            self.log = MessageLog(o.out / "messages.jsonl", self.clock,
                                  {sd.stream: self.team_reg for sd in self.sides.values()}, self.ref_reg,
                                  key=o.key if self.legacy else keys)
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
        for side in self.sides.values():
            self._start_teamserver(side, o)
        for side in self.sides.values():
            for n in side.robot_numbers:
                self.start_agent(n, restarted=False, team=side.color)
            side.recorder = Recorder(self.world, self.refbox, side.color, side.robot_numbers, o.sample_period,
                                     snapshot=side.teamserver.snapshot)
        if self.watch is not None:
            self.recorder.listeners.append(self.watch.recorded)

    def _state_file(self, side: Side, o: GameOptions) -> Path:
        """Where ``side``'s team server keeps its database."""
        name = "teamserver.sqlite" if self.legacy else f"teamserver-{side.color.lower()}.sqlite"
        if o.state is not None:
            return o.state if self.legacy else o.state.with_name(f"{o.state.stem}-{side.color.lower()}.sqlite")
        if o.out is not None:
            state = o.out / name
            if state.exists():
                state.unlink()
            return state
        if self._tmp is None:
            self._tmp = tempfile.TemporaryDirectory(prefix="rll-bt-sim-")
        return Path(self._tmp.name) / name

    def _start_teamserver(self, side: Side, o: GameOptions) -> None:
        t = side.team
        truth = ({n: s.zone for n, s in self.refbox.stations().items()} if t.strategy == "oracle" else None)
        bus, reg, key, stream = self.bus, self.ref_reg, t.key, side.stream
        side.teamserver = load_teamserver(t.teamserver)(
            profile=o.profile, team_name=t.name, key=key, clock=self.clock,
            refbox_public=lambda: bus.peer("public", registry=reg, name=stream),
            refbox_team=lambda color: bus.peer(color.lower(), registry=reg, name=stream),
            agents=lambda: agent_link.bus_server(bus, stream, key=key),
            state=str(self._state_file(side, o)), strategy=t.strategy, seed=o.seed, oracle=truth,
            options=TeamServerOptions(baseline=t.baseline, map_period=o.map_period, extra=t.extra))

    # -- the first side's parts, as in a game of one team ------------------------------------
    @property
    def home(self) -> Side:
        return next(iter(self.sides.values()))

    @property
    def teamserver(self):
        return self.home.teamserver

    @property
    def agents(self) -> dict[int, RobotAgent]:
        return self.home.agents

    @property
    def robot_numbers(self) -> list[int]:
        return self.home.robot_numbers

    @property
    def recorder(self) -> Recorder:
        return self.home.recorder

    def side(self, team: str | None) -> Side:
        """The side playing ``team`` (a colour; None: the first side)."""
        if team is None:
            return self.home
        try:
            return self.sides[team.upper()]
        except KeyError:
            raise ValueError(f"no {team} team in this game (teams: {', '.join(self.sides)})") from None

    # -- parts -------------------------------------------------------------------------
    def start_agent(self, number: int, restarted: bool = True, known_pose: bool = True,
                    team: str | None = None) -> RobotAgent:
        """A new agent for robot ``number`` of ``team`` (default the first side)
        (its robot stays where it is; the agent starts from the robot's true
        pose, as an operator would set it, or with ``known_pose=False`` finds
        it by global localisation)."""
        o, bus, reg = self.options, self.bus, self.ref_reg
        side = self.side(team)
        t, color = side.team, side.color
        name = f"R{number}" if self.legacy else f"{t.prefix}-R{number}"
        cfg = AgentConfig(robot_id=number, team_name=t.name, profile=o.profile, hz=o.hz)
        backend = self.world.backend(color, number)
        watched = self.watch is not None and side is self.home
        rw = self.watch.robot(number) if watched else None
        link = agent_link.bus_client(bus, side.stream, key=t.key, name=name)
        faults = o.net.for_robot(number)
        if faults is not None:        # the robot's radio: seeded per game, robot and start of its agent
            self._links_made += 1
            link = FaultyTransport(link, faults, seed=f"{o.seed}/{name}/{self._links_made}", clock=self.clock,
                                   stream=True)
        agent = RobotAgent(
            cfg, clock=self.clock, backend=backend if rw is None else rw.tap(backend), link=link,
            public=bus.peer("public", registry=reg, name=name),
            team=lambda c: bus.peer(c.lower(), registry=reg, key=t.key, name=name),
            services={"localisation": o.localisation},
            start_pose=self.world.robot_pose(color, number) if known_pose else None, restarted=restarted)
        side.agents[number] = agent
        if rw is not None:
            rw.attach(agent)
        if restarted:
            self._note("agent started", side, robot=number)
        return agent

    def kill_agent(self, number: int, team: str | None = None) -> None:
        """The agent dies without a goodbye: its links drop, its robot stops
        once the last drive command times out."""
        side = self.side(team)
        agent = side.agents.pop(number)
        side.recorder.task(number, None, outcome="agent killed")
        agent.link.close()
        agent.refbox.close()
        self._note("agent killed", side, robot=number)

    def restart_teamserver(self, team: str | None = None) -> None:
        side = self.side(team)
        side.teamserver.restart()
        self._note("team server restarted", side)

    def station_down(self, machine: str, seconds: float) -> None:
        self.refbox.station_down(machine, seconds)
        self._note("station down", machine=machine, seconds=seconds)

    def _note(self, what: str, side: Side | None = None, **data) -> None:
        """A note in ``side``'s recording (every side's for None: a fault of the field)."""
        for sd in ([side] if side is not None else self.sides.values()):
            if sd.recorder is not None:
                sd.recorder.note(what, **data)

    # -- running -------------------------------------------------------------------------
    def start(self) -> None:
        if not self._started:
            self._started = True
            self.refbox.start()
            if self.watch is not None:
                self.watch.stations()
            for side in self.sides.values():
                side.recorder.sample(force=True)

    def round(self) -> None:
        """One lockstep round of ``dt`` seconds."""
        for side in self.sides.values():
            for n in sorted(side.agents):
                agent = side.agents[n]
                before = agent.run
                agent.step()
                run = agent.run
                ended = before.outcome.status if before is not None and before.done else None
                if run is not None and not run.done:
                    side.recorder.task(n, run.kind, run.task_id, outcome=ended)
                else:
                    side.recorder.task(n, None, outcome=ended)
        self.world.step(self.options.dt)
        self.refbox.step()
        for side in self.sides.values():
            side.teamserver.tick()
        self.rounds += 1
        if self.watch is not None:
            self.watch.round()
        if self.pace is not None:
            self._keep_real_time()
        before = len(self.recorder.rec.samples)
        for side in self.sides.values():
            side.recorder.sample()
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
            limit = self.options.expected_duration() + self.options.overtime_length() + 60.0
        end = self.clock.now() + limit
        done = False
        while self.clock.now() < end:
            if self.finished() or (stop is not None and stop(self)):
                done = True
                break
            self.round()
        done = done or self.finished()
        for side in self.sides.values():
            side.recorder.sample(force=True)
            side.recorder.close_tasks()
        result = self.result(done)
        if self.watch is not None:
            self.watch.result(result)
        return result

    def result(self, finished: bool) -> GameResult:
        collisions = self.world.collision_log()
        snaps = {c: sd.teamserver.snapshot() for c, sd in self.sides.items()}
        return GameResult(finished=finished, status=self.refbox.status(), recording=self.recorder.rec,
                          awards=self.refbox.awards(), deliveries=self.refbox.deliveries(),
                          snapshot=snaps[self.home.color], stations=self.refbox.stations(),
                          orders=self.refbox.orders(), collisions=len(collisions),
                          tally={c: self.refbox.tally(c) for c in self.sides},
                          sim_time=self.clock.now(), messages=self.bus.frames,
                          collision_log=collisions,
                          recordings={c: sd.recorder.rec for c, sd in self.sides.items()}, snapshots=snaps,
                          labels={c: sd.team.label for c, sd in self.sides.items()},
                          sightings=self.world.laser_sightings())

    def close(self) -> None:
        for side in self.sides.values():
            for agent in side.agents.values():
                try:
                    agent.shutdown()
                except Exception:
                    pass
        for side in self.sides.values():
            if side.teamserver is not None:
                side.teamserver.close()
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
