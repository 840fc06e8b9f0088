"""The PyBullet world and the simulated refbox as one game for ``rll-bt sim``.

Entry point ``rll_bt.simulators: pybullet`` -> :func:`open_game`, which
returns a :class:`PyBulletGame` implementing
:class:`rll_bt.game.interfaces.Simulation`: a :class:`~backends.sim.world.World`
whose clock everything runs on, and a :class:`~backends.sim.refbox.RefboxGame`
that drives its stations, put on the in-process bus (lockstep) or on UDP
(one process per part).  Robots are :class:`~backends.sim.backend.SimBackend`.
Times are seconds of the world's clock; game times are the refbox's.
"""
from __future__ import annotations

import dataclasses

from rll_bt.backend import Pose2D
from rll_bt.game.interfaces import Award, Delivery, GameStatus, Simulation, StationTruth

from .backend import SimBackend
from .refbox import RefboxGame, RefboxNode, Timing
from .refbox import events as E
from .world import World


class PyBulletGame(Simulation):
    """``profile`` and ``seed`` fix the layout, lights, orders and down periods;
    ``team_name``/``key`` the team playing cyan; ``phases`` overrides phase
    lengths in game seconds ({"setup": 10, ...}); ``world_step`` is the
    world's longest physics sub-step (s); ``robot_options`` are
    :class:`~backends.sim.robot.RobotConfig` fields for every robot."""

    def __init__(self, profile: str = "rcll2016", seed: int = 0, *, team_name: str, key: str,
                 perception: str = "oracle", gui: bool = False, phases: dict | None = None,
                 world_step: float = 0.05, robot_options: dict | None = None):
        self.world = World(profile, seed, perception=perception, gui=gui, time_step=world_step)
        self.profile = self.world.profile
        self.clock = self.world.clock
        self.seed = int(seed)
        self.team_name, self.key = team_name, key
        timing = Timing.from_profile(self.profile, **(phases or {}))
        self.game = RefboxGame(self.profile, self.clock, self.world, seed=seed, team_cyan=team_name,
                               timing=timing)
        self.robot_options = dict(robot_options or {})
        self.node: RefboxNode | None = None

    # -- wiring ------------------------------------------------------------------------
    def attach_bus(self, bus) -> None:
        self.node = RefboxNode.on_bus(self.game, bus, keys={self.team_name: self.key})

    def attach_udp(self, host: str = "127.0.0.1", port_layout="sim") -> None:
        """``host``: where the refbox sends (a broadcast address for several
        listeners on one machine); ``port_layout``: a name or a
        :class:`rll_bt.comm.Layout`.  No control stream."""
        self.node = RefboxNode.on_udp(self.game, host=host, layout=port_layout,
                                      keys={self.team_name: self.key}, stream_port=-1)

    def tap(self, fn) -> None:
        if self.node is None:
            raise RuntimeError("attach the refbox to a bus or to UDP first")
        ch = self.node.channels
        ch.public = _Tapped(ch.public, "public", fn)
        ch.team = {color: _Tapped(t, color.lower(), fn) for color, t in ch.team.items()}
        if ch.stream is not None:
            ch.stream = _Tapped(ch.stream, "stream", fn)

    def refbox_registry(self):
        return RefboxNode.registry(self.game)

    def start(self) -> None:
        self.game.start()

    def step(self, dt: float) -> None:
        self.world.step(dt)

    def refbox_step(self) -> None:
        if self.node is None:
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
        g = self.game
        return GameStatus(g.phase, g.state, g.game_time, g.timing.length(g.phase),
                          {t: g.points(t) for t in ("CYAN", "MAGENTA")})

    def awards(self) -> list[Award]:
        return list(self.game.ledger.entries)       # the ledger keeps Award records

    def deliveries(self) -> list[Delivery]:
        return [Delivery(e.team, e.game_time, int(e.points or 0), e.data.get("order"),
                         str(e.data.get("how", ""))) for e in self.game.events if e.kind == E.DELIVERY]

    def stations(self) -> dict[str, StationTruth]:
        out = {}
        for name in self.world.machines:
            st = self.world.station(name)
            ref = self.game.stations.get(name)
            light = ()
            if hasattr(self.game.exploration, "code_of"):          # 2016: the type's light code
                light = tuple(sorted(self.profile.light_code(self.game.exploration.code_of(name))))
            out[name] = StationTruth(name, st.team, int(st.zone), int(st.rotation), st.pose,
                                     ref.state if ref is not None else "IDLE", light)
        return out

    def orders(self) -> list[dict]:
        out = []
        for o in self.game.orders:
            d = {f.name: getattr(o, f.name) for f in dataclasses.fields(o)}
            d["rings"] = list(d["rings"])
            out.append(d)
        return out

    # -- faults ------------------------------------------------------------------------------
    def station_down(self, machine: str, seconds: float) -> None:
        """A down period starting now (the refbox's own down periods, ahead of time)."""
        st = self.game.stations[machine]
        if self.game.phase != "PRODUCTION":
            raise RuntimeError(f"stations go DOWN only in PRODUCTION (now {self.game.phase})")
        now = self.game.game_time
        st.down, st.down_done = (now, now + float(seconds)), False
        self.game.tick()
        st.update(self.game.game_time)

    def close(self) -> None:
        if self.node is not None:
            self.node.close()
        self.world.close()


class _Tapped:
    """A refbox transport that shows ``fn`` every message it sends and receives."""

    def __init__(self, inner, channel: str, fn):
        self._inner, self._channel, self._fn = inner, channel, fn

    def send(self, msg, *args, **kw):
        sent = self._inner.send(msg, *args, **kw)
        if sent:
            self._fn(self._channel, "refbox", msg)
        return sent

    def receive(self):
        got = self._inner.receive()
        for rec in got:
            self._fn(self._channel, str(rec.source), rec.msg)
        return got

    def __getattr__(self, name):
        return getattr(self._inner, name)


def open_game(**options) -> PyBulletGame:
    """Entry point ``rll_bt.simulators: pybullet`` (options of :class:`PyBulletGame`)."""
    return PyBulletGame(**options)
