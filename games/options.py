"""What one simulated game is: rules, seed, team, and the speed knobs.

Speed knobs (what ``make sim`` is tuned with): ``dt`` is the lockstep step
(s of simulated time per round of agents, world, refbox and team server);
``hz`` the agents' tree tick rate; ``laser_rate`` the simulated laser's
scans per second; ``localisation`` the localiser preset ("cheap" for whole
games, "standard" for accuracy); ``world_step`` the world's longest physics
sub-step (s).  Phase lengths are game seconds; ``None`` keeps the rules'.

The values of the options the plug-ins interpret are theirs to publish
(:func:`rll_bt.plugins.offers`): ``perception`` the simulator's,
``strategy`` the team server's, ``localisation`` the tree-node plug-ins'
(the skills build the localiser); :func:`published` reads them.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

from rll_bt import plugins, rules
from rll_bt.comm.faults import NetFaults
from rll_bt.contracts import SIMULATORS, TEAMSERVERS, TeamServerOptions, check_teamserver

from .teams import Team, TeamSpec, lineup

UNTIL = ("exploration", "end")
#: option -> (entry point group publishing its values, the GameOptions field naming
#: the entry point, or None: every entry point of the group)
PUBLISHED = {"perception": (SIMULATORS, "simulator"), "strategy": (TEAMSERVERS, "teamserver"),
             "localisation": ("rll_bt.nodes", None)}
HARDWARE = ("none", "emulated")
REFBOXES = ("simulated", "external")
CONTROLS = ("auto", "manual")
STATIONS = ("mqtt", "opcua")
#: the emulated rig's lasers (backends.robotino.rig.LASERS: games reach backends through entry points only)
LASERS = ("urg", "urg-tcp", "tim")
TEAM_NAME = "GRIPS"
TEAM_KEY = "rll-bt-sim-key"


@dataclass
class GameOptions:
    profile: str = rules.DEFAULT
    robots: int = 3
    seed: int = 1
    perception: str = "oracle"
    strategy: str = "algorithm1"
    until: str = "end"
    gui: bool = False
    out: Path | None = None
    processes: bool = False
    hardware: str = "none"               # "emulated": agents on the robotino backend over device emulators
    laser: str = "urg"                   # the emulated laser: "urg" (SCIP 2.0, pty) or "tim" (CoLa, TCP)
    camera_fps: float = 5.0              # frames per second the emulated cameras serve
    # phase lengths (game seconds); None: the rules' own
    setup: float | None = 10.0
    exploration: float | None = None
    production: float | None = None
    overtime: float | None = None        # added to PRODUCTION when two teams are tied (None: the rules')
    # speed knobs
    dt: float = 0.05
    hz: float = 10.0
    laser_rate: float = 10.0
    localisation: str = "cheap"
    world_step: float = 0.05
    # parts
    simulator: str = "pybullet"
    teamserver: str = "htn"
    baseline: bool = False
    map_period: float = 5.0
    team_name: str = TEAM_NAME
    key: str = TEAM_KEY
    state: Path | None = None          # team server database (default: in ``out`` or a temp dir)
    sample_period: float = 1.0         # s between recorder samples
    record: Path | None = None         # an MCAP recording of the game (games.watch)
    live: int | None = None            # Foxglove WebSocket port for a live view (0: any free)
    record_camera: float = 0.0         # camera frames taken for the recording itself, per robot and second
    view: int | None = None            # port of the live page (games.view; 0: any free)
    speed: float | None = None         # game seconds per wall second; 0: as fast as possible;
                                       # None: real time when watched (gui, live, view), else as fast as possible
    # a refbox elsewhere (``refbox="external"``, :mod:`games.external`)
    refbox: str = "simulated"
    refbox_host: str = "127.0.0.1"
    refbox_port_offset: int = 0        # its ports: the refbox's "sim" layout moved by this
    refbox_control: str = "auto"       # "auto": this game names the team and switches the phases
    stations: str = "mqtt"             # how the world's stations are served to it
    mqtt: str | None = None            # the broker ("HOST:PORT"; default the refbox host's 1883)
    opcua_base_port: int = 4840
    refbox_timeout: float = 180.0      # s to wait for the refbox and its field
    game: Path | None = None           # a stored game to play (its field, orders, ring setup, down periods)
    save_game: Path | None = None      # write the game in that form at its start
    # a lossy radio on every robot's team-server link (both ways), seeded by ``seed``
    net: NetFaults = field(default_factory=NetFaults)
    extra: dict = field(default_factory=dict)
    # two teams (games.teams): a CONFIG per colour; both None: the single team above plays cyan
    cyan: TeamSpec | str | None = None
    magenta: TeamSpec | str | None = None

    def __post_init__(self) -> None:
        for color in ("cyan", "magenta"):
            spec = getattr(self, color)
            if isinstance(spec, str):
                setattr(self, color, TeamSpec.parse(spec))
        if self.profile not in rules.PROFILES:
            raise ValueError(f"unknown profile {self.profile!r} (known: {', '.join(rules.PROFILES)})")
        if not 1 <= int(self.robots) <= 3:
            raise ValueError(f"robots must be 1, 2 or 3, not {self.robots}")
        self.robots = int(self.robots)
        if self.until not in UNTIL:
            raise ValueError(f"until must be one of {', '.join(UNTIL)}, not {self.until!r}")
        for name, allowed in (("hardware", HARDWARE), ("laser", LASERS)):
            if getattr(self, name) not in allowed:
                raise ValueError(f"{name} must be one of {', '.join(allowed)}, not {getattr(self, name)!r}")
        for name, allowed in (("refbox", REFBOXES), ("refbox_control", CONTROLS), ("stations", STATIONS)):
            if getattr(self, name) not in allowed:
                raise ValueError(f"{name} must be one of {', '.join(allowed)}, not {getattr(self, name)!r}")
        if not self.refbox_timeout > 0:
            raise ValueError(f"refbox_timeout must be positive, not {self.refbox_timeout}")
        if not 0 <= int(self.refbox_port_offset) <= 60000:
            raise ValueError(f"refbox_port_offset must be 0..60000, not {self.refbox_port_offset}")
        if self.refbox == "external" and (self.game is not None or self.save_game is not None):
            raise ValueError("a refbox elsewhere draws its own game: no --game or --save-game")
        if self.refbox == "external" and self.hardware != "none":
            raise ValueError("--hardware emulated plays against the simulated refbox only")
        for name, (group, field_name) in PUBLISHED.items():
            plugin = getattr(self, field_name) if field_name else None
            try:
                allowed = plugins.choices(group, name, plugin)
            except KeyError as exc:
                raise ValueError(exc.args[0]) from None
            if getattr(self, name) not in allowed:
                raise ValueError(f"{name} must be one of {', '.join(allowed)}, not {getattr(self, name)!r}")
        for name in ("dt", "hz", "laser_rate", "world_step", "sample_period"):
            if not getattr(self, name) > 0:
                raise ValueError(f"{name} must be positive, not {getattr(self, name)}")
        for name in ("setup", "exploration", "production"):
            v = getattr(self, name)
            if v is not None and v < 0:
                raise ValueError(f"{name} must be >= 0 seconds, not {v}")
        if self.speed is not None and not self.speed >= 0:
            raise ValueError(f"speed must be >= 0 (0: as fast as possible), not {self.speed}")
        for name in ("out", "game", "save_game"):
            if getattr(self, name) is not None:
                setattr(self, name, Path(getattr(self, name)))
        self._check_teams()

    def _check_teams(self) -> None:
        teams = self.lineup()
        for team in teams.values():
            if team.external:
                if not self.processes:
                    raise ValueError(f"an external team ({team.color.lower()}) plays over the network: "
                                     "give --processes")
                continue
            try:
                strategies = plugins.choices(TEAMSERVERS, "strategy", team.teamserver)
                settings = plugins.choices(TEAMSERVERS, "setting", team.teamserver)
            except KeyError as exc:
                raise ValueError(f"{team.color.lower()} team {team.label!r}: {exc.args[0]}") from None
            if strategies and team.strategy not in strategies:
                raise ValueError(f"{team.color.lower()} team {team.label!r}: strategy must be one of "
                                 f"{', '.join(strategies)}, not {team.strategy!r}")
            if team.spec is not None and settings:
                unknown = [n for n in team.spec.server_settings if n not in settings]
                if unknown:
                    raise ValueError(f"{team.color.lower()} team {team.label!r}: {team.teamserver} has no setting "
                                     f"{', '.join(unknown)} (settings: {', '.join(settings)})")
            if team.spec is not None and team.spec.server_settings:
                try:
                    check_teamserver(team.teamserver, TeamServerOptions(extra=team.spec.server_settings))
                except ValueError as exc:
                    raise ValueError(f"{team.color.lower()} team {team.label!r}: {exc}") from None
        if all(t.external for t in teams.values()):
            raise ValueError("both teams are external: nothing of ours would play")
        if self.hardware == "emulated" and len(teams) > 1:
            raise ValueError("--hardware emulated plays one team")
        if getattr(self, "refbox", "sim") == "external" and len(teams) > 1:
            raise ValueError("--refbox external plays one team of ours")

    def lineup(self) -> dict[str, Team]:
        """The teams of this game by colour, cyan first (:func:`games.teams.lineup`)."""
        return lineup(self)

    @property
    def head_to_head(self) -> bool:
        """Two teams on the field."""
        return self.cyan is not None and self.magenta is not None

    @property
    def pace(self) -> float:
        """Game seconds per wall second a lockstep game keeps to (0: as fast as it goes)."""
        if self.speed is not None:
            return float(self.speed)
        return 1.0 if self.gui or self.live is not None or self.view is not None else 0.0

    @property
    def rules(self):
        return rules.profile(self.profile)

    def external(self) -> dict:
        """The simulator's ``external`` arguments (``refbox="external"``)."""
        return {"host": self.refbox_host, "port": 4444 + int(self.refbox_port_offset),
                "control": self.refbox_control, "stations": self.stations, "broker": self.mqtt,
                "opcua_base_port": self.opcua_base_port, "timeout": self.refbox_timeout}

    def stored(self) -> dict:
        """The stored-game arguments of the simulator's factory."""
        return {"stored_game": self.game, "save_game": self.save_game}

    def phases(self) -> dict[str, float]:
        """The phase-length overrides for the simulator (game seconds)."""
        return {k: float(v) for k in ("setup", "exploration", "production", "overtime")
                if (v := getattr(self, k)) is not None}

    def phase_lengths(self) -> dict[str, float]:
        """Every phase's length as played (overrides applied)."""
        p = self.rules.phases
        out = {"SETUP": p.setup, "EXPLORATION": p.exploration, "PRODUCTION": p.production}
        for k, v in self.phases().items():
            if k == "overtime" or (k == "exploration" and p.exploration_in_production > 0):
                continue
            out[k.upper()] = v
        return out

    def exploration_window(self) -> float:
        """Game seconds of exploration (its own phase, or the start of PRODUCTION)."""
        p = self.rules.phases
        if p.exploration_in_production > 0:
            return float(self.exploration if self.exploration is not None else p.exploration_in_production)
        return float(self.exploration if self.exploration is not None else p.exploration)

    def exploration_over(self, status) -> bool:
        """Whether exploration is over at ``status`` (a :class:`~.interfaces.GameStatus`)."""
        if self.rules.phases.exploration_in_production > 0:
            return status.phase == "PRODUCTION" and status.game_time >= self.exploration_window()
        return status.phase in ("PRODUCTION", "POST_GAME")

    def game_over(self, status) -> bool:
        """Whether the game as asked for (``until``) is over at ``status``."""
        return status.phase == "POST_GAME" or (self.until == "exploration" and self.exploration_over(status))

    def overtime_length(self) -> float:
        """Game seconds a tie adds to PRODUCTION."""
        return float(self.overtime if self.overtime is not None else self.rules.phases.overtime)

    def expected_duration(self) -> float:
        """Simulated seconds of the whole game (or until exploration ends), no overtime."""
        lengths = self.phase_lengths()
        if self.until == "exploration":
            if self.rules.phases.exploration_in_production > 0:
                return lengths["SETUP"] + self.exploration_window()
            return lengths["SETUP"] + lengths["EXPLORATION"]
        return sum(lengths.values())


def published(option: str, plugin: str | None = None) -> tuple[str, ...]:
    """The values of ``option`` ("perception", "strategy", "localisation") the
    plug-ins publish: of entry point ``plugin`` (a simulator or team server
    name; None: all of the group)."""
    group, _field = PUBLISHED[option]
    return plugins.choices(group, option, plugin)


def max_exploration_points(profile) -> int:
    """Points for reporting every own station right (type, zone, rotation as the rules ask)."""
    s, reports = profile.scoring, profile.exploration_reports
    per = s.explore_zone_ok
    if "type" in reports:
        per += s.explore_type_ok
    if "rotation" in reports:
        per += s.explore_rotation_ok
    return per * len(profile.machine_types)
