"""The team server as one part of a simulated game (``rll-bt sim``).

Entry point ``rll_bt.teamservers: htn`` -> :func:`open_teamserver`, which
returns an :class:`InProcessTeamServer` implementing
:class:`rll_bt.contracts.TeamServerHandle`: a :class:`TeamServer` on
the transports the game hands it, that can be killed and restarted from its
state database mid-game, and that reports its view for the game report.

``options.baseline`` plays the greedy baseline of the benchmarks instead of
the HTN production choice (``ServerConfig.planner = "greedy"``: one order at
a time, the one with the earliest deadline that can be planned, no
look-ahead, so no caps retrieved ahead either; see
:class:`~teamserver.planning.planner.GreedyPlanner`).
"""
from __future__ import annotations

import dataclasses

from rll_bt.contracts import TeamServerHandle, TeamServerOptions
from rll_bt.plugins import offers

from .exploration.strategies import STRATEGIES
from .exploration.symmetry import consistent_set
from .exploration.view import sure_properties
from .knowledge import model as M
from .links.refbox_link import RefboxLink
from .server import ServerConfig, TeamServer


class InProcessTeamServer(TeamServerHandle):
    """See the module doc.  ``refbox_public()`` and ``agents()`` make new
    transports (called again on :meth:`restart`); ``refbox_team(color)`` the
    team channel once our colour is known."""

    def __init__(self, *, profile, team_name: str, key: str, clock, refbox_public, refbox_team,
                 agents, state: str, strategy: str = "algorithm1", seed: int = 0,
                 oracle: dict | None = None, options: TeamServerOptions | None = None):
        self.options = options or TeamServerOptions()
        self._args = {"profile": profile, "team_name": team_name, "key": key, "clock": clock}
        self._public, self._team, self._agents = refbox_public, refbox_team, agents
        self.state = state
        cfg = ServerConfig(strategy=strategy, seed=seed, map_period=self.options.map_period,
                           planner="greedy" if self.options.baseline else "htn")
        if self.options.baseline:
            cfg.max_products = 1
            cfg.prefill_caps = False        # no look-ahead: no caps retrieved for later orders
        configure(cfg, self.options.extra)
        self.config = cfg
        self.oracle = oracle
        self.restarts = 0
        self.server = self._make()

    def _make(self) -> TeamServer:
        a = self._args
        link = RefboxLink(self._public(), self._team)
        return TeamServer(a["profile"], a["team_name"], clock=a["clock"], refbox=link,
                          agents=self._agents(), key=a["key"], state=self.state,
                          config=self.config, oracle=self.oracle)

    def tick(self) -> None:
        self.server.tick()

    def restart(self) -> None:
        old = self.server
        old.agents.close()
        if old.refbox_link is not None:
            old.refbox_link.close()
        old.close()
        self.restarts += 1
        self.server = self._make()

    def snapshot(self) -> dict:
        kb = self.server.kb
        robots = {}
        for r in kb.robots.values():
            t = kb.tasks.get(r.task_id) if r.task_id is not None else None
            robots[r.number] = {"task": t.kind if t is not None and t.state == M.ASSIGNED else None,
                                "task_id": r.task_id, "status": r.status}
        tasks = [{"id": t.id, "kind": t.kind, "state": t.state, "robot": t.robot,
                  "machine": t.machine, "product": t.product, "assigned_at": t.assigned_at,
                  "finished_at": t.finished_at, "error": t.error} for t in kb.tasks.values()]
        color = self.server.color
        known = {}
        if color is not None:
            cs = consistent_set(self.server.profile, kb.machines)
            for name, guess in (cs.machines.items() if cs else ()):
                sure = sure_properties(self.server.profile, guess, self.config.explore_thresh)
                if sure:
                    known[name] = sure
        delivered = sum(1 for p in kb.products.values() if p.state == "DELIVERED")
        stations = {name: st.state for name, st in kb.stations.items()}
        return {"robots": robots, "tasks": tasks, "known": known, "delivered": delivered,
                "stations": stations, "phase": self.server.refbox.phase,
                "color": color, "restarts": self.restarts}

    def close(self) -> None:
        srv = self.server
        srv.agents.close()
        if srv.refbox_link is not None:
            srv.refbox_link.close()
        srv.close()


#: the ServerConfig fields a team configuration may set by name (``htn:replan_period=5``)
SETTINGS = tuple(f.name for f in dataclasses.fields(ServerConfig)
                 if f.type in ("str", "int", "float", "bool", "int | None") and f.name not in ("strategy", "seed"))


def configure(cfg: ServerConfig, extra: dict) -> None:
    """Set ``extra`` on ``cfg``: objects as they are (tests pass a DispatchConfig),
    the named scalar :data:`SETTINGS` checked against their field's type;
    ``ValueError`` for an unknown name or a value of the wrong type."""
    types = {f.name: f.type for f in dataclasses.fields(ServerConfig)}
    for name, value in extra.items():
        if name not in types:
            raise ValueError(f"the team server has no setting {name!r} (settings: {', '.join(SETTINGS)})")
        kind = types[name]
        if name in SETTINGS:
            ok = {"bool": isinstance(value, bool), "str": isinstance(value, str),
                  "int": isinstance(value, int) and not isinstance(value, bool),
                  "int | None": value is None or (isinstance(value, int) and not isinstance(value, bool)),
                  "float": isinstance(value, int | float) and not isinstance(value, bool)}[kind]
            if not ok:
                raise ValueError(f"team server setting {name} takes {kind}, not {value!r}")
            if kind == "float":
                value = float(value)
        setattr(cfg, name, value)


def check_options(options: TeamServerOptions) -> None:
    """What :func:`open_teamserver` would refuse in ``options`` (``ValueError``), without starting it."""
    configure(ServerConfig(), options.extra)


@offers(strategy=tuple(STRATEGIES), setting=SETTINGS, planner=("htn", "greedy"))
def open_teamserver(**options) -> InProcessTeamServer:
    """Entry point ``rll_bt.teamservers: htn`` (options of :class:`InProcessTeamServer`);
    publishes the exploration strategies it plays (``choices["strategy"]``)."""
    return InProcessTeamServer(**options)


open_teamserver.check = check_options
