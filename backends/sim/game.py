"""The PyBullet world and the simulated refbox as one game for ``rll-bt sim``.

Entry point ``rll_bt.simulators: pybullet`` -> :func:`open_game`, which
returns a :class:`rll_bt.contracts.Simulation`: a :class:`PyBulletWorld`
(a :class:`~backends.sim.world.World` whose clock everything runs on) and
the simulated refbox that drives its stations.  With ``refbox="here"``
(lockstep) that is :class:`RefboxHere`, a
:class:`~backends.sim.refbox.RefboxGame` in this process, put on the
in-process bus.  With ``refbox="process"`` (``rll-bt sim --processes``)
this process holds only the world: :class:`RefboxOverLink` serves the
stations over the station link (:mod:`backends.sim.refbox.link`) to a
refbox of its own process, ``rll-bt refbox sim --world remote:HOST:PORT``
(the command line :meth:`RefboxOverLink.command` gives), and reads the game
from the snapshot file that process rewrites (:mod:`backends.sim.refbox.view`).
With ``refbox="external"`` (``rll-bt sim --refbox external``) the refbox
runs elsewhere, the real one or ours: :mod:`.external` builds the world on
its field, serves it the stations and its clock.  Robots are
:class:`~backends.sim.backend.SimBackend`.  Times are seconds of the
world's clock; game times are the refbox's.
"""
from __future__ import annotations

from pathlib import Path

from rll_bt.backend import Pose2D
from rll_bt.contracts import (
    Award,
    Delivery,
    GameStatus,
    InProcessRefbox,
    RefboxProcess,
    Simulation,
    StationTruth,
    Tally,
    World,
)
from rll_bt.errors import UserError
from rll_bt.plugins import offers

from .backend import SimBackend
from .refbox import RefboxGame, RefboxNode, Timing
from .refbox.view import GameView, SnapshotView
from .world import PERCEPTION_MODES
from .world import World as Physics

REFBOX_MODES = ("here", "process", "external")
SNAPSHOT_PERIOD = 0.25       # s between two snapshots of a refbox process
#: frames a second a robot's camera delivers in a game with rendered perception (the detectors
#: run on each: at 2 Hz blinking a light is still seen on and off)
GAME_CAMERA_RATE = 5.0


class PyBulletWorld(World):
    """The :class:`rll_bt.contracts.World` of a PyBullet world (``pybullet``:
    the :class:`~backends.sim.world.World` itself, for tests that move
    robots and workpieces by hand).  ``robot_options`` are
    :class:`~backends.sim.robot.RobotConfig` fields for every robot (with
    rendered perception a camera delivers :data:`GAME_CAMERA_RATE` frames a
    second unless ``camera_rate`` says otherwise)."""

    def __init__(self, profile: str = "rcll2016", seed: int = 0, *, perception: str = "oracle", gui: bool = False,
                 world_step: float = 0.05, robot_options: dict | None = None, layout=None):
        self.pybullet = Physics(profile, seed, perception=perception, gui=gui, time_step=world_step, layout=layout)
        self.profile = self.pybullet.profile
        self.clock = self.pybullet.clock
        self.seed = int(seed)
        self.robot_options = dict(robot_options or {})
        if perception == "rendered":
            self.robot_options.setdefault("camera_rate", GAME_CAMERA_RATE)

    def step(self, dt: float) -> None:
        self.pybullet.step(dt)

    def backend(self, team: str, number: int, **options) -> SimBackend:
        key = (team.upper(), int(number))
        if key in self.pybullet.robots:
            return SimBackend(self.pybullet, key)
        return SimBackend(self.pybullet, key, **{**self.robot_options, **options})

    def emulated_hardware(self, *, laser: str = "urg", camera_fps: float = 5.0, devices: str = "threads"):
        """Every robot as emulated devices fed by this world (:mod:`.hardware`):
        ``add((team, n))`` gives a rig whose ``config()`` is the robot
        configuration for the robotino backend; ``sync()`` after each step."""
        from .hardware import WorldHardware
        return WorldHardware(self.pybullet, laser=laser, camera_fps=camera_fps, devices=devices)

    def robot_pose(self, team: str, number: int) -> Pose2D:
        return self.pybullet.robot_pose(team, number)

    def collision_log(self) -> list[tuple[float, str, str]]:
        return [(c.time, f"{c.robot[0]}/{c.robot[1]}", str(c.obstacle)) for c in self.pybullet.collision_log]

    def laser_sightings(self) -> dict[str, dict[str, int]]:
        return self.pybullet.laser_sightings()

    def close(self) -> None:
        self.pybullet.close()


class _ViewOfWorld:
    """The refbox view of a PyBullet game: the refbox's game (``self.view``,
    a :class:`GameView` or :class:`SnapshotView`) with the world's stations."""

    world: PyBulletWorld
    view: GameView | SnapshotView

    def status(self) -> GameStatus:
        return self.view.status()

    def awards(self) -> list[Award]:
        return self.view.awards()

    def deliveries(self) -> list[Delivery]:
        return self.view.deliveries()

    def stations(self) -> dict[str, StationTruth]:
        states, lights, w = self.view.station_states(), self.view.light_codes(), self.world.pybullet
        out = {}
        for name in w.machines:
            st = w.station(name)
            out[name] = StationTruth(name, st.team, int(st.zone), int(st.rotation), st.pose,
                                     states.get(name, "IDLE"), lights.get(name, ()))
        return out

    def orders(self) -> list[dict]:
        return self.view.orders()

    def station_log(self) -> list[dict]:
        """Every station state change the refbox made (see :mod:`.refbox.view`)."""
        return self.view.station_log()

    def tally(self, team: str) -> Tally:
        return self.view.tally(team)


def _teams(team_name: str, key: str, teams: dict | None) -> dict[str, tuple[str, str]]:
    """colour -> (team name, key): ``teams`` when given, else ``team_name`` playing cyan."""
    if not teams:
        return {"CYAN": (team_name, key)}
    out = {c.upper(): (str(n), str(k)) for c, (n, k) in teams.items()}
    bad = set(out) - {"CYAN", "MAGENTA"}
    if bad:
        raise ValueError(f"team colours are CYAN and MAGENTA, not {', '.join(sorted(bad))}")
    return out


class RefboxHere(_ViewOfWorld, InProcessRefbox):
    """The simulated refbox in this process on the world's clock.  ``teams``:
    colour -> (team name, key) of each team playing (default: ``team_name``
    with ``key`` playing cyan); ``phases``: phase lengths in game seconds
    ({"setup": 10, ...})."""

    def __init__(self, world: PyBulletWorld, *, team_name: str, key: str, phases: dict | None = None,
                 stored=None, save_game: str | None = None, teams: dict | None = None):
        from .refbox.stored_game import play_stored, store_game
        self.world = world
        self.teams = _teams(team_name, key, teams)
        timing = Timing.from_profile(world.profile, **{k: float(v) for k, v in (phases or {}).items()})
        names = {c: n for c, (n, _k) in self.teams.items()}
        self.game = RefboxGame(world.profile, world.clock, world.pybullet, seed=world.seed,
                               team_cyan=names.get("CYAN"), team_magenta=names.get("MAGENTA"), timing=timing)
        if stored is not None:
            play_stored(self.game, stored)
        if save_game is not None:
            store_game(self.game, name=stored.name if stored is not None else "").save(save_game)
        self.view = GameView(self.game)
        self.node: RefboxNode | None = None

    def attach_bus(self, bus) -> None:
        self.node = RefboxNode.on_bus(self.game, bus, keys=dict(self.teams.values()))

    def attach_udp(self, *, host: str, layout, stream_port: int = -1) -> None:
        """Put the refbox on UDP on this world's clock (``host``: where it sends,
        e.g. the loopback broadcast; ``layout``: a :class:`rll_bt.comm.Layout`
        or its name, the refbox's view; ``stream_port``: the plain TCP control
        stream, -1 none): teams of other processes play in this world."""
        self.node = RefboxNode.on_udp(self.game, host=host, layout=layout, keys=dict(self.teams.values()),
                                      stream_port=stream_port)

    def start(self) -> None:
        self.game.start()

    def step(self) -> None:
        if self.node is None:
            self.game.tick()
        else:
            self.node.step()

    def station_down(self, machine: str, seconds: float) -> None:
        """A down period starting now (the refbox's own down periods, ahead of time)."""
        self.game.station_down(machine, seconds)

    def close(self) -> None:
        if self.node is not None:
            self.node.close()


class RefboxOverLink(_ViewOfWorld, RefboxProcess):
    """The simulated refbox as a process of its own: this side serves it the
    world's stations (a :class:`~.refbox.link.StationServer`) and reads its
    snapshot.  ``team_name``, ``key`` and ``phases`` as for :class:`RefboxHere`."""

    def __init__(self, world: PyBulletWorld, *, team_name: str, key: str, phases: dict | None = None,
                 stored=None, save_game: str | None = None, stored_file: str | None = None,
                 teams: dict | None = None):
        from .refbox.link import StationServer
        self.world = world
        self.teams = _teams(team_name, key, teams)
        self.phases = {k: float(v) for k, v in (phases or {}).items()}
        self.stored_file, self.save_game = stored_file, save_game
        self.link = StationServer(world.pybullet)
        self.view = SnapshotView(None)

    def command(self, *, host: str, layout, snapshot: Path, message_log: Path | None = None) -> list[str]:
        self.view = SnapshotView(snapshot)
        ports = ",".join(f"{ch}={layout.refbox(ch).send}/{layout.refbox(ch).recv}"
                         for ch in ("public", "cyan", "magenta"))
        args = ["refbox", "sim", "--profile", self.world.profile.name, "--seed", str(self.world.seed),
                *self._team_args(), "--host", host, "--ports", ports,
                "--no-stream", "--start", "command", "--mockup", "off",
                "--world", f"remote:127.0.0.1:{self.link.port}", "--snapshot", str(snapshot),
                "--snapshot-period", str(SNAPSHOT_PERIOD)]
        if self.phases:
            args += ["--phase-lengths", ",".join(f"{k}={v!r}" for k, v in self.phases.items())]
        if message_log is not None:
            args += ["--message-log", str(message_log)]
        if self.stored_file is not None:
            args += ["--game", str(self.stored_file)]
        if self.save_game is not None:
            args += ["--save-game", str(self.save_game)]
        return args

    def _team_args(self) -> list[str]:
        out = []
        for color, (name, key) in self.teams.items():
            out += [f"--team-{color.lower()}", name, f"--key-{color.lower()}={key}"]
        return out

    def ready(self) -> bool:
        return self.view.ready

    def start(self) -> None:
        self.link.command("start")

    def step(self) -> None:
        self.link.clock(self.world.pybullet.time)    # the refbox process's clock follows the world's
        self.link.poll(0.0)          # the refbox process's calls

    def station_down(self, machine: str, seconds: float) -> None:
        """An operator command to the refbox process: a down period starting now."""
        if machine not in self.world.pybullet.machines:
            raise ValueError(f"no station {machine!r}")
        phase = self.status().phase
        if phase != "PRODUCTION":
            raise RuntimeError(f"stations go DOWN only in PRODUCTION (now {phase})")
        self.link.command("down", machine=machine, seconds=float(seconds))

    def close(self) -> None:
        self.link.close()


def load_stored(path: str | Path, profile: str):
    """The stored game at ``path`` for a world of ``profile``; a
    :class:`~rll_bt.errors.UserError` naming the file when it cannot be read
    or plays another profile."""
    from .stored import StoredGameError, load_game
    try:
        stored = load_game(str(path))
    except StoredGameError as exc:
        raise UserError(str(exc), where="--game") from None
    if stored.profile != profile:
        raise UserError(f"the stored game is {stored.profile}, the game plays {profile}", where="--game",
                        hint=f"add --profile {stored.profile}")
    return stored


@offers(perception=PERCEPTION_MODES)
def open_game(profile: str = "rcll2016", seed: int = 0, *, team_name: str | None, key: str | None,
              perception: str = "oracle", gui: bool = False, phases: dict | None = None, world_step: float = 0.05,
              robot_options: dict | None = None, refbox: str = "here", stored_game: str | Path | None = None,
              save_game: str | Path | None = None, external: dict | None = None,
              teams: dict | None = None) -> Simulation:
    """Entry point ``rll_bt.simulators: pybullet``: a :class:`PyBulletWorld` and
    its refbox (``refbox``: "here", "process" or "external", see the module
    doc; "external": ``external`` holds :func:`.external.open_external`'s
    keywords, the refbox's address, its control, the stations' wire) for the
    ``teams`` (colour -> (team name, key); default ``team_name`` playing cyan);
    publishes its perception modes (``choices["perception"]``).
    ``stored_game``: a stored game's file (:mod:`.stored`) whose field the
    world takes and whose orders, ring setup and down periods the refbox
    plays; ``save_game``: where the refbox writes its game as one."""
    if refbox not in REFBOX_MODES:
        raise ValueError(f"refbox must be one of {', '.join(REFBOX_MODES)}, not {refbox!r}")
    if refbox == "external":
        from rll_bt import rules

        from .external import open_external
        if stored_game is not None or save_game is not None:
            raise UserError("a refbox elsewhere draws its own game", where="--game/--save-game")

        def build(layout):
            return PyBulletWorld(profile, seed, perception=perception, gui=gui, world_step=world_step,
                                 robot_options=robot_options, layout=layout)
        world, made = open_external(build, rules.profile(profile), team_name=team_name, **(external or {}))
        return Simulation(world, made)
    stored = load_stored(stored_game, profile) if stored_game is not None else None
    world = PyBulletWorld(profile, seed, perception=perception, gui=gui, world_step=world_step,
                          robot_options=robot_options, layout=stored.layout(seed) if stored is not None else None)
    save = str(save_game) if save_game is not None else None
    try:
        if refbox == "here":
            made = RefboxHere(world, team_name=team_name, key=key, phases=phases, stored=stored, save_game=save,
                              teams=teams)
        else:
            made = RefboxOverLink(world, team_name=team_name, key=key, phases=phases, save_game=save,
                                  stored_file=str(Path(stored_game).resolve()) if stored_game is not None else None,
                                  teams=teams)
        return Simulation(world, made)
    except BaseException:
        world.close()
        raise
