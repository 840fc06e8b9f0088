"""The PyBullet world and the simulated refbox as one game for ``rll-bt sim``.

Entry point ``rll_bt.simulators: pybullet`` -> :func:`open_game`, which
returns a :class:`PyBulletGame` implementing
:class:`rll_bt.contracts.Simulation`: a :class:`~backends.sim.world.World`
whose clock everything runs on, and the simulated refbox that drives its
stations.  With ``refbox="here"`` (lockstep) that is a
:class:`~backends.sim.refbox.RefboxGame` in this process, put on the
in-process bus.  With ``refbox="process"`` (``rll-bt sim --processes``)
this process holds only the world: it serves the stations over the station
link (:mod:`backends.sim.refbox.link`) to a refbox of its own process,
``rll-bt refbox sim --world remote:HOST:PORT`` (the command line
:meth:`PyBulletGame.refbox_command` gives), and reads the game from the
snapshot file that process rewrites (:mod:`backends.sim.refbox.view`).
Robots are :class:`~backends.sim.backend.SimBackend`.  Times are seconds of
the world's clock; game times are the refbox's.
"""
from __future__ import annotations

from pathlib import Path

from rll_bt.backend import Pose2D
from rll_bt.contracts import Award, Delivery, GameStatus, Simulation, StationTruth
from rll_bt.plugins import offers

from .backend import SimBackend
from .refbox import RefboxGame, RefboxNode, Timing
from .refbox.view import GameView, SnapshotView
from .world import PERCEPTION_MODES, World

REFBOX_MODES = ("here", "process")
SNAPSHOT_PERIOD = 0.25       # s between two snapshots of a refbox process


class PyBulletGame(Simulation):
    """``profile`` and ``seed`` fix the layout, lights, orders and down periods;
    ``team_name``/``key`` the team playing cyan; ``phases`` overrides phase
    lengths in game seconds ({"setup": 10, ...}); ``world_step`` is the
    world's longest physics sub-step (s); ``robot_options`` are
    :class:`~backends.sim.robot.RobotConfig` fields for every robot;
    ``refbox``: "here" (the refbox in this process on the world's clock) or
    "process" (see the module doc)."""

    def __init__(self, profile: str = "rcll2016", seed: int = 0, *, team_name: str, key: str,
                 perception: str = "oracle", gui: bool = False, phases: dict | None = None,
                 world_step: float = 0.05, robot_options: dict | None = None, refbox: str = "here"):
        if refbox not in REFBOX_MODES:
            raise ValueError(f"refbox must be one of {', '.join(REFBOX_MODES)}, not {refbox!r}")
        self.world = World(profile, seed, perception=perception, gui=gui, time_step=world_step)
        self.profile = self.world.profile
        self.clock = self.world.clock
        self.seed = int(seed)
        self.team_name, self.key = team_name, key
        self.phases = {k: float(v) for k, v in (phases or {}).items()}
        self.robot_options = dict(robot_options or {})
        self.node: RefboxNode | None = None
        self.game: RefboxGame | None = None
        self.link = None
        if refbox == "here":
            timing = Timing.from_profile(self.profile, **self.phases)
            self.game = RefboxGame(self.profile, self.clock, self.world, seed=seed, team_cyan=team_name,
                                   timing=timing)
            self.view = GameView(self.game)
        else:
            from .refbox.link import StationServer
            self.link = StationServer(self.world)
            self.view = SnapshotView(None)

    # -- wiring ------------------------------------------------------------------------
    def attach_bus(self, bus) -> None:
        if self.game is None:
            raise RuntimeError("this game's refbox runs in a process of its own")
        self.node = RefboxNode.on_bus(self.game, bus, keys={self.team_name: self.key})

    def refbox_command(self, *, host: str, layout, snapshot: Path, message_log: Path | None = None) -> list[str]:
        """``rll-bt`` arguments running the refbox as its own process on UDP
        (``host``: where it sends; ``layout``: a :class:`rll_bt.comm.Layout`,
        the refbox's view), on this world's stations over the station link,
        rewriting ``snapshot`` (read back by :meth:`status` and the rest) and
        logging its messages to ``message_log`` (JSON lines, wall clock)."""
        if self.link is None:
            raise RuntimeError("this game's refbox runs here (refbox='here')")
        self.view = SnapshotView(snapshot)
        ports = ",".join(f"{ch}={layout.refbox(ch).send}/{layout.refbox(ch).recv}"
                         for ch in ("public", "cyan", "magenta"))
        args = ["refbox", "sim", "--profile", self.profile.name, "--seed", str(self.seed),
                "--team-cyan", self.team_name, f"--key-cyan={self.key}", "--host", host, "--ports", ports,
                "--no-stream", "--start", "command", "--mockup", "off",
                "--world", f"remote:127.0.0.1:{self.link.port}", "--snapshot", str(snapshot),
                "--snapshot-period", str(SNAPSHOT_PERIOD)]
        if self.phases:
            args += ["--phase-lengths", ",".join(f"{k}={v!r}" for k, v in self.phases.items())]
        if message_log is not None:
            args += ["--message-log", str(message_log)]
        return args

    def refbox_ready(self) -> bool:
        return self.game is not None or self.view.ready

    def refbox_registry(self):
        from rll_bt import msgs
        from rll_bt.comm import MessageRegistry
        return MessageRegistry.from_message_set(msgs.message_set(self.profile.name))

    def start(self) -> None:
        if self.game is not None:
            self.game.start()
        else:
            self.link.command("start")

    def step(self, dt: float) -> None:
        self.world.step(dt)

    def refbox_step(self) -> None:
        if self.link is not None:
            self.link.poll(0.0)          # the refbox process's calls
        elif self.node is None:
            self.game.tick()
        else:
            self.node.step()

    # -- robots ------------------------------------------------------------------------
    def backend(self, team: str, number: int, **options) -> SimBackend:
        key = (team.upper(), int(number))
        if key in self.world.robots:
            return SimBackend(self.world, key)
        return SimBackend(self.world, key, **{**self.robot_options, **options})

    def robot_pose(self, team: str, number: int) -> Pose2D:
        return self.world.robot_pose(team, number)

    def collisions(self) -> int:
        return self.world.collision_count

    def collision_log(self) -> list[tuple[float, str, str]]:
        return [(c.time, f"{c.robot[0]}/{c.robot[1]}", str(c.obstacle)) for c in self.world.collision_log]

    # -- reading the game -----------------------------------------------------------------
    def status(self) -> GameStatus:
        return self.view.status()

    def awards(self) -> list[Award]:
        return self.view.awards()

    def deliveries(self) -> list[Delivery]:
        return self.view.deliveries()

    def stations(self) -> dict[str, StationTruth]:
        states, lights = self.view.station_states(), self.view.light_codes()
        out = {}
        for name in self.world.machines:
            st = self.world.station(name)
            out[name] = StationTruth(name, st.team, int(st.zone), int(st.rotation), st.pose,
                                     states.get(name, "IDLE"), lights.get(name, ()))
        return out

    def orders(self) -> list[dict]:
        return self.view.orders()

    def station_log(self) -> list[dict]:
        """Every station state change the refbox made (see :mod:`.refbox.view`)."""
        return self.view.station_log()

    # -- faults ------------------------------------------------------------------------------
    def station_down(self, machine: str, seconds: float) -> None:
        """A down period starting now (the refbox's own down periods, ahead of time)."""
        if self.game is not None:
            self.game.station_down(machine, seconds)
            return
        if machine not in self.world.machines:
            raise ValueError(f"no station {machine!r}")
        phase = self.status().phase
        if phase != "PRODUCTION":
            raise RuntimeError(f"stations go DOWN only in PRODUCTION (now {phase})")
        self.link.command("down", machine=machine, seconds=float(seconds))

    def close(self) -> None:
        if self.node is not None:
            self.node.close()
        if self.link is not None:
            self.link.close()
        self.world.close()


@offers(perception=PERCEPTION_MODES)
def open_game(**options) -> PyBulletGame:
    """Entry point ``rll_bt.simulators: pybullet`` (options of :class:`PyBulletGame`);
    publishes its perception modes (``choices["perception"]``)."""
    return PyBulletGame(**options)
