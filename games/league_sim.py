"""Other teams' software in rll-bt's world: ``rll-bt sim --external-team COLOR --teamserver HOST:PORT``.

    game = ExternalGame([ExternalTeam("CYAN", ("127.0.0.1", 2016), "Carologistics", "randomkey")],
                        profile="rcll2025", seed=3)
    game.connect(timeout=60)           # until every robot is connected to its team server
    game.run()                         # the whole game on the wall clock
    game.close()

This process is the league's simulator for the teams named: it holds the
PyBullet world, the simulated refbox and the simulated robots of each
external team.  Each robot is an rll-bt agent speaking only the league's
messages (:attr:`~rll_bt.agent.AgentConfig.league_only`): a TCP client of
its team's team server (plain protobuf_comm frames, reconnecting until the
server is there), taking ``AgentTask`` and sending ``BeaconSignal`` with the
current and finished tasks, running rll-bt's trees for each task and
answering with the league's error codes.  Like the league simulator's
robots they find the stations themselves: from the refbox's MachineInfo
(once a station is reported right, and for all of them once the
exploration time is over) and from what they see.

The refbox is on UDP on this process's clock (which follows the wall
clock, or runs ``speed`` times faster than it): it sends to ``host`` (default the loopback broadcast address, so
that every process on the machine hears it) with the refbox's default port
layout ``sim`` (public: refbox sends 4444, listens 4445; cyan 4441/4446;
magenta 4442/4447; a team server listens where the refbox sends and sends
where it listens), each team channel encrypted with that team's key.  The
game starts once every robot is connected.  See ``docs/league.md``.
"""
from __future__ import annotations

import logging
import time
from collections.abc import Callable
from dataclasses import dataclass

from rll_bt.agent import AgentConfig, RobotAgent
from rll_bt.agent.network import RefboxAddress, refbox_channels
from rll_bt.agenttask import link as agent_link
from rll_bt.clock import WallClock
from rll_bt.comm import Layout
from rll_bt.comm import layout as get_layout
from rll_bt.contracts import GameStatus, load_simulator

log = logging.getLogger("games.league_sim")

BROADCAST = "127.255.255.255"
COLORS = ("CYAN", "MAGENTA")


@dataclass(frozen=True)
class ExternalTeam:
    """A team whose team server runs elsewhere: ``color`` "CYAN"/"MAGENTA",
    ``server`` (host, port) its robots connect to, ``name`` and ``key`` as the
    refbox knows them, ``robots`` how many it has (1..3)."""
    color: str
    server: tuple[str, int]
    name: str
    key: str
    robots: int = 3

    def __post_init__(self) -> None:
        if self.color not in COLORS:
            raise ValueError(f"team colour must be CYAN or MAGENTA, not {self.color!r}")
        if not 1 <= int(self.robots) <= 3:
            raise ValueError(f"robots must be 1, 2 or 3, not {self.robots}")


class ExternalGame:
    """See the module doc.  ``layout``: the refbox's port layout (a
    :class:`~rll_bt.comm.Layout` or "sim"/"competition"); ``phases``: phase
    lengths in game seconds ({"setup": 10, ...}); ``hz`` the robots' tree
    tick rate; ``localisation`` their localiser preset; ``speed`` game seconds per
    wall second (default 1, real time; above 1 the game clock and every time
    stamp the robots and the refbox send run that much faster than Unix time,
    from the moment the game was made, as the league simulator's simulated
    time does; the other team's software must then keep its time from those
    stamps or the refbox's game time, not from its own wall clock)."""

    def __init__(self, teams: list[ExternalTeam], *, profile: str = "rcll2025", seed: int = 1,
                 host: str = BROADCAST, layout: Layout | str = "sim", phases: dict | None = None,
                 perception: str = "oracle", hz: float = 10.0, localisation: str = "cheap",
                 world_step: float = 0.05, simulator: str = "pybullet", wall=None, speed: float = 1.0):
        if not speed > 0:
            raise ValueError(f"speed must be > 0 game seconds per wall second, not {speed}")
        self.speed = float(speed)
        colors = [t.color for t in teams]
        if not teams or len(set(colors)) != len(colors):
            raise ValueError("give one or two external teams of different colours")
        self.teams = {t.color: t for t in teams}
        self.wall = wall or WallClock()
        self.layout = layout if isinstance(layout, Layout) else get_layout(layout)
        self.host = host
        self.world_step = world_step
        cyan, magenta = self.teams.get("CYAN"), self.teams.get("MAGENTA")
        self.sim = load_simulator(simulator)(
            profile=profile, seed=seed, team_name=(cyan or magenta).name, key=(cyan or magenta).key,
            teams={c: (t.name, t.key) for c, t in self.teams.items()}, perception=perception, gui=False,
            phases=phases or {}, world_step=world_step)
        self.world, self.refbox = self.sim.world, self.sim.refbox
        self.clock = self.world.clock
        self.clock.sync_epoch(self.wall_epoch())      # beacons and refbox times in real Unix time
        self.agents: dict[tuple[str, int], RobotAgent] = {}
        try:
            self.refbox.attach_udp(host=host, layout=self.layout)
            for t in teams:
                for n in range(1, t.robots + 1):
                    self.agents[(t.color, n)] = self._agent(t, n, profile, hz, localisation)
        except BaseException:
            self.close()
            raise
        self._last = self.wall.now()
        self.started = False
        self.hooks: list[Callable[[ExternalGame], None]] = []    # run after every round

    def _agent(self, team: ExternalTeam, n: int, profile: str, hz: float, localisation: str) -> RobotAgent:
        host, port = team.server
        robot = self.layout.robot
        addr = RefboxAddress(self.host, "sim", robot("public").recv, robot("public").send,
                             robot(team.color.lower()).recv, robot(team.color.lower()).send)
        public, team_channel = refbox_channels(addr, profile, key=team.key, clock=self.clock)
        config = AgentConfig(robot_id=n, team_name=team.name, profile=profile, color=team.color, hz=hz,
                             league_only=True)
        link = agent_link.tcp_client(host, port, key=None, clock=self.clock, backoff_initial=0.5, backoff_max=5.0)
        return RobotAgent(config, clock=self.clock, backend=self.world.backend(team.color, n), link=link,
                          public=public, team=team_channel, services={"localisation": localisation},
                          start_pose=self.world.robot_pose(team.color, n), restarted=False)

    @staticmethod
    def wall_epoch() -> float:
        return time.time()

    # -- running -------------------------------------------------------------------------
    def round(self) -> None:
        """Step the robots, then the world by the wall time that passed (at most
        0.1 s) times ``speed``, then the refbox; waits a moment when less than
        half a world step would pass."""
        now = self.wall.now()
        dt = min(now - self._last, 0.1) * self.speed
        if dt < self.world_step * 0.5 - 1e-9:
            self.wall.sleep((self.world_step * 0.5 - dt) / self.speed)
            return
        self._last = now
        if self.speed == 1.0:
            epoch = self.wall_epoch()
            if abs(self.clock.epoch() - epoch) > 0.5:     # the world fell behind: stamps stay real time
                self.clock.sync_epoch(epoch)
        for key in sorted(self.agents):
            self.agents[key].step()
        self.world.step(dt)
        self.refbox.step()
        for hook in list(self.hooks):
            hook(self)

    def connected(self) -> list[tuple[str, int]]:
        """The robots connected to their team server."""
        return [k for k, a in self.agents.items() if a.connected]

    def connect(self, timeout: float = 60.0, progress: Callable[[list], None] | None = None) -> bool:
        """Run (the game not started) until every robot is connected to its team
        server, at most ``timeout`` wall seconds; whether they all are."""
        end = self.wall.now() + timeout
        while len(self.connected()) < len(self.agents) and self.wall.now() < end:
            self.round()
            if progress is not None:
                progress(self.connected())
        return len(self.connected()) == len(self.agents)

    def start(self) -> None:
        """Start the game (the operator's RUNNING)."""
        if not self.started:
            self.started = True
            self.refbox.start()

    def status(self) -> GameStatus:
        return self.refbox.status()

    def over(self) -> bool:
        return self.status().phase == "POST_GAME"

    def run_until(self, predicate: Callable[[ExternalGame], bool], limit: float) -> bool:
        """Start the game if it is not, then run until ``predicate(game)`` or
        ``limit`` more seconds; whether it held."""
        self.start()
        end = self.clock.now() + limit
        while self.clock.now() < end:
            if predicate(self):
                return True
            self.round()
        return predicate(self)

    def run(self, limit: float | None = None, progress: Callable | None = None) -> bool:
        """Play until the game is over (or ``limit`` seconds); whether it is over."""
        self.start()
        end = self.clock.now() + (limit if limit is not None else 1e9)
        last = -1e9
        while self.clock.now() < end and not self.over():
            self.round()
            if progress is not None and self.clock.now() - last >= 1.0:
                last = self.clock.now()
                progress(self.clock.now(), self.status())
        return self.over()

    def close(self) -> None:
        for agent in self.agents.values():
            try:
                agent.close()
            except Exception:
                log.exception("closing an agent failed")
        self.agents.clear()
        self.sim.close()

    def __enter__(self) -> ExternalGame:
        return self

    def __exit__(self, *exc) -> None:
        self.close()
