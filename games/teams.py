"""Who plays: a team configuration (``--cyan CONFIG``, ``--magenta CONFIG``,
``rll-bt tournament CONFIG...``) and the line-up of a game.

A CONFIG is a kind and optional settings::

    CONFIG  := KIND [":" SETTING ("," SETTING)*]
    SETTING := NAME "=" VALUE

Kinds:

- ``htn``: the project's team server (HTN production planning);
- ``baseline``: the same team server with the greedy one-order-at-a-time
  production instead of the HTN planner (``TeamServerOptions.baseline``);
- ``external``: another team's software, playing through the refbox's real
  network protocol (its team channel, its key); only with ``--processes``.
  Its robots are its own: none of ours are put on the field for it;
- any other name of the ``rll_bt.teamservers`` entry point group (a team
  server a plug-in adds).

Settings the game reads: ``strategy`` (the exploration strategy, one the
team server publishes), ``robots`` (1-3), ``name`` (the team name the
refbox knows it by) and ``key`` (its crypto key).  Every other setting goes
to the team server (``TeamServerOptions.extra``), which checks it: for
``htn`` and ``baseline`` the scalar fields of its ``ServerConfig``, e.g.
``htn:replan_period=5,plan_max_evaluations=120``.  Values are read as
booleans (``true``/``false``), integers, numbers, else text.  Examples::

    htn                          baseline:strategy=nearest
    htn:strategy=random,robots=2 external:name=Carologistics,key=randomkey

A setting a game-wide option also gives (``rll-bt sim --strategy``,
``--robots``) falls back to that option when the CONFIG does not say.
"""
from __future__ import annotations

import re
from dataclasses import dataclass, field

from rll_bt.rules import CYAN, MAGENTA, TEAMS

EXTERNAL = "external"
BASELINE = "baseline"
GAME_SETTINGS = ("strategy", "robots", "name", "key")
#: the team names and keys a colour gets when its CONFIG names none
DEFAULT_NAMES = {CYAN: "GRIPS", MAGENTA: "GRIPS-M"}
DEFAULT_KEYS = {CYAN: "rll-bt-sim-key", MAGENTA: "rll-bt-sim-key-magenta"}
_NAME = re.compile(r"^[A-Za-z][A-Za-z0-9_.-]*$")


def _value(text: str):
    low = text.lower()
    if low in ("true", "false"):
        return low == "true"
    for kind in (int, float):
        try:
            return kind(text)
        except ValueError:
            pass
    return text


@dataclass(frozen=True)
class TeamSpec:
    """A parsed CONFIG: ``kind`` and ``settings`` (name -> value, in the order given)."""

    kind: str
    settings: tuple[tuple[str, object], ...] = ()

    @classmethod
    def parse(cls, text: str) -> TeamSpec:
        """``ValueError`` naming what is wrong with ``text``."""
        text = (text or "").strip()
        kind, _, rest = text.partition(":")
        kind = kind.strip()
        if not _NAME.match(kind):
            raise ValueError(f"team configuration {text!r}: give a kind (htn, baseline, external, ...) first")
        settings: dict[str, object] = {}
        for part in (p.strip() for p in rest.split(",")) if rest.strip() else ():
            name, eq, value = part.partition("=")
            name, value = name.strip(), value.strip()
            if not eq or not _NAME.match(name) or not value:
                raise ValueError(f"team configuration {text!r}: {part!r} is not NAME=VALUE")
            if name in settings:
                raise ValueError(f"team configuration {text!r}: {name} given twice")
            settings[name] = value if name in ("name", "key") else _value(value)
        spec = cls(kind, tuple(settings.items()))
        spec._check()
        return spec

    def _check(self) -> None:
        s = self.get
        if s("robots") is not None and s("robots") not in (1, 2, 3):
            raise ValueError(f"team configuration {self}: robots must be 1, 2 or 3, not {s('robots')!r}")
        if self.external:
            extra = [n for n, _ in self.settings if n not in ("name", "key")]
            if extra:
                raise ValueError(f"team configuration {self}: an external team takes only name and key, "
                                 f"not {', '.join(extra)}")
        if s("strategy") is not None and not isinstance(s("strategy"), str):
            raise ValueError(f"team configuration {self}: strategy must be a name")

    def get(self, name: str, default=None):
        return dict(self.settings).get(name, default)

    @property
    def external(self) -> bool:
        return self.kind == EXTERNAL

    @property
    def teamserver(self) -> str:
        """The ``rll_bt.teamservers`` entry point playing it (``baseline`` is ``htn``'s)."""
        return "htn" if self.kind == BASELINE else self.kind

    @property
    def server_settings(self) -> dict:
        """The settings that go to the team server."""
        return {n: v for n, v in self.settings if n not in GAME_SETTINGS}

    def __str__(self) -> str:
        if not self.settings:
            return self.kind
        return self.kind + ":" + ",".join(f"{n}={str(v).lower() if isinstance(v, bool) else v}"
                                          for n, v in self.settings)


@dataclass(frozen=True)
class Team:
    """One side of a game as played: ``color``, its ``spec`` (None: the
    options' own single team), refbox ``name`` and ``key``, ``robots``, the
    exploration ``strategy``, the team server entry point and its options."""

    color: str
    name: str
    key: str
    robots: int
    strategy: str
    teamserver: str = "htn"
    baseline: bool = False
    extra: dict = field(default_factory=dict)
    spec: TeamSpec | None = None

    @property
    def external(self) -> bool:
        return self.spec is not None and self.spec.external

    @property
    def label(self) -> str:
        """The CONFIG it plays (``htn``/``baseline`` for the options' own team)."""
        if self.spec is not None:
            return str(self.spec)
        return BASELINE if self.baseline else self.teamserver

    @property
    def prefix(self) -> str:
        return self.color[0]


def lineup(options) -> dict[str, Team]:
    """The teams of a game (:class:`~.options.GameOptions`), cyan first.
    Without ``cyan``/``magenta`` the options' own single team plays cyan."""
    specs = {CYAN: options.cyan, MAGENTA: options.magenta}
    if not any(specs.values()):
        return {CYAN: Team(CYAN, options.team_name, options.key, options.robots, options.strategy,
                           options.teamserver, options.baseline, dict(options.extra))}
    out: dict[str, Team] = {}
    for color in TEAMS:
        spec = specs[color]
        if spec is None:
            continue
        name = spec.get("name") or (options.team_name if color == CYAN else DEFAULT_NAMES[color])
        key = spec.get("key") or (options.key if color == CYAN else DEFAULT_KEYS[color])
        out[color] = Team(color, name, key, int(spec.get("robots") or options.robots),
                          spec.get("strategy") or options.strategy, spec.teamserver,
                          spec.kind == BASELINE, {**options.extra, **spec.server_settings}, spec)
    names = [t.name for t in out.values()]
    if len(set(names)) != len(names):
        raise ValueError(f"both teams are named {names[0]!r}: give one another name (name=...)")
    return out


def joining(team: Team, layout, host: str) -> dict:
    """What an external ``team`` needs to join a game: the refbox's UDP
    ``host``, its ports as a robot sees them ([send, recv] per channel, from
    the game's ``layout``) and the team's name and key (the game also writes
    it to ``external-<colour>.json``)."""
    if not team.external:
        raise ValueError(f"the {team.color.lower()} team is ours")
    ch = team.color.lower()
    ports = {c: [layout.robot(c).send, layout.robot(c).recv] for c in ("public", ch)}
    return {"team": team.name, "key": team.key, "color": team.color, "host": host, "ports": ports}

