"""The central knowledge base: what the team knows, written through to SQLite.

Holds machine observations (fused per property), robots, orders, station
states, workpieces, tasks, products, visited zones and what was reported.
Every mutating method persists at once; :meth:`KnowledgeBase.load` rebuilds
the same state from the database after a restart.  The observations are kept
as they came until the store holds ``observation_limit`` of them; then they
are folded into what the beliefs hold (each robot's vote per visit, its
latest pose; :meth:`KnowledgeBase.fold_observations`): reloaded, the folded
rows make exactly the same beliefs, so nothing a decision needs is lost.  The
table holds at most the limit or twice the beliefs' votes, whichever is more
(a robot votes again only after ``revisit_gap`` s of silence about a property).
"""
from __future__ import annotations

from collections.abc import Iterable
from typing import Any

from rll_bt.rules import Profile

from . import model as M
from .fusion import DiscreteBelief, Estimate, PoseBelief
from .store import Store

REFBOX = "refbox"          # the "robot" name of ground truth released by the refbox
#: observation rows the store holds before they are folded into the beliefs' votes
OBSERVATION_LIMIT = 5000


class MachineBelief:
    """The fused beliefs about one machine, one per property."""

    def __init__(self, name: str, profile: Profile):
        self.name = name
        self.props: dict[str, DiscreteBelief | PoseBelief] = {
            M.ZONE: DiscreteBelief(len(profile.zones.all_zones)),
            M.ORIENTATION: DiscreteBelief(360 // profile.rotation_step_deg),
            M.LIGHT: DiscreteBelief(max(len(profile.light_codes), 2)),
            M.TYPE: DiscreteBelief(5),
            M.POSE: PoseBelief(),
        }

    def estimate(self, prop: str) -> Estimate | None:
        return self.props[prop].estimate()

    def confidence(self, prop: str) -> float:
        est = self.estimate(prop)
        return 0.0 if est is None else est.confidence

    @property
    def observed(self) -> bool:
        return any(not b.empty for b in self.props.values())


class KnowledgeBase:
    """In-memory state plus its write-through :class:`Store`."""

    def __init__(self, profile: Profile, store: Store | None = None, *, observation_limit: int = OBSERVATION_LIMIT):
        self.profile = profile
        self.store = store if store is not None else Store(":memory:")
        self.machines: dict[str, MachineBelief] = {}
        self.observation_count = 0              # observations fused since the game began
        self.observation_limit = observation_limit
        self.observation_rows = 0               # rows the store holds
        self.folds = 0                          # times they were folded (this process)
        self._fold_at = observation_limit
        self.robots: dict[int, M.Robot] = {}
        self.orders: dict[int, M.Order] = {}
        self.stations: dict[str, M.Station] = {}
        self.workpieces: dict[str, M.Workpiece] = {}
        self.tasks: dict[int, M.Task] = {}
        self.products: dict[str, M.Product] = {}
        self.visited: dict[int, float] = {}          # zone -> server time of the visit
        self.reported: dict[str, dict[str, Any]] = {}  # machine -> {prop: value sent}
        self.meta: dict[str, Any] = {}

    # -- restart ----------------------------------------------------------------
    @classmethod
    def load(cls, profile: Profile, store: Store, *, observation_limit: int = OBSERVATION_LIMIT) -> KnowledgeBase:
        """The knowledge base as persisted in ``store`` (empty for a new database)."""
        kb = cls(profile, store, observation_limit=observation_limit)
        saved = store.get_meta("profile")
        if saved is not None and saved != profile.name:
            from rll_bt.errors import UserError
            raise UserError(f"state database holds a {saved} game, not {profile.name}",
                            where=store.path, hint="use another --state file")
        if saved is None:
            store.set_meta("profile", profile.name)
        for machine, prop, value, conf, robot, t in store.observations():
            kb._fuse(M.Observation(machine, prop, value, conf, robot, t))
        kb.observation_rows = kb.observation_count
        kb.observation_count += int(store.get_meta("observations_folded", 0))
        for attr, kind, rec, keyf in cls._TABLES:
            table = getattr(kb, attr)
            for key, data in store.all(kind):
                table[keyf(key)] = rec.from_dict(data)
        for key, data in store.all("visited"):
            kb.visited[int(key)] = float(data)
        for key, data in store.all("reported"):
            kb.reported[key] = dict(data)
        for key, data in store.all("meta"):
            kb.meta[key] = data
        return kb

    _TABLES = (
        ("robots", "robot", M.Robot, int),
        ("orders", "order", M.Order, int),
        ("stations", "station", M.Station, str),
        ("workpieces", "workpiece", M.Workpiece, str),
        ("tasks", "task", M.Task, int),
        ("products", "product", M.Product, str),
    )

    # -- machine observations -------------------------------------------------
    def machine(self, name: str) -> MachineBelief:
        mb = self.machines.get(name)
        if mb is None:
            if name not in self.profile.tags:
                raise ValueError(f"{self.profile.name} has no machine {name!r}")
            mb = self.machines[name] = MachineBelief(name, self.profile)
        return mb

    def add_observation(self, obs: M.Observation) -> None:
        """Fuse ``obs`` and persist it."""
        self._fuse(obs)
        self.store.add_observation(obs.machine, obs.prop, obs.value, obs.confidence,
                                   obs.robot, obs.time)
        self.observation_rows += 1
        if self.observation_rows > self._fold_at:
            self.fold_observations()

    def fold_observations(self) -> None:
        """Replace the stored observations by the beliefs' votes (see the module doc)."""
        rows = [(name, prop, list(v) if isinstance(v, tuple) else v, c, robot, t)
                for name, mb in self.machines.items() for prop, belief in mb.props.items()
                for robot, v, c, t in belief.rows()]
        self.store.replace_observations(rows, {"observations_folded": self.observation_count - len(rows)})
        self.observation_rows = len(rows)
        self.folds += 1
        self._fold_at = max(self.observation_limit, 2 * len(rows))

    def _fuse(self, obs: M.Observation) -> None:
        belief = self.machine(obs.machine).props[obs.prop]
        value = tuple(obs.value) if isinstance(obs.value, list) else obs.value
        if obs.robot == REFBOX or M.is_view_source(obs.robot):
            # the refbox's truth, and a robot's view of a tower: its latest statement replaces the last
            belief.add_fixed(obs.robot, value, obs.confidence, obs.time)
        else:
            belief.add(obs.robot, value, obs.confidence, obs.time)
        self.observation_count += 1

    def estimate(self, machine: str, prop: str) -> Estimate | None:
        mb = self.machines.get(machine)
        return None if mb is None else mb.estimate(prop)

    def observed_machines(self) -> list[str]:
        return sorted(n for n, mb in self.machines.items() if mb.observed)

    def machine_position(self, machine: str) -> tuple[float, float] | None:
        """Best known position of ``machine`` (fused pose, else its zone's centre)."""
        st = self.stations.get(machine)
        pose = self.estimate(machine, M.POSE)
        if pose is not None:
            return pose.value[0], pose.value[1]
        zone = self.estimate(machine, M.ZONE)
        if zone is not None:
            return self.profile.zone_centre(int(zone.value))
        if st is not None and st.zone is not None:
            return self.profile.zone_centre(st.zone)
        fixed = self.profile.fixed_zones.get(machine)
        return self.profile.zone_centre(fixed) if fixed is not None else None

    # -- zones -----------------------------------------------------------------
    def mark_visited(self, zone: int, t: float) -> None:
        self.visited[zone] = t
        self.store.put("visited", zone, t)

    # -- reports ---------------------------------------------------------------
    def mark_reported(self, machine: str, values: dict[str, Any]) -> None:
        cur = self.reported.setdefault(machine, {})
        cur.update(values)
        self.store.put("reported", machine, cur)

    # -- records -----------------------------------------------------------------
    def save_robot(self, r: M.Robot) -> None:
        self.robots[r.number] = r
        self.store.put("robot", r.number, r.to_dict())

    def save_order(self, o: M.Order) -> None:
        self.orders[o.id] = o
        self.store.put("order", o.id, o.to_dict())

    def save_station(self, s: M.Station) -> None:
        self.stations[s.name] = s
        self.store.put("station", s.name, s.to_dict())

    def save_workpiece(self, w: M.Workpiece) -> None:
        self.workpieces[w.id] = w
        self.store.put("workpiece", w.id, w.to_dict())

    def save_task(self, t: M.Task) -> None:
        self.tasks[t.id] = t
        self.store.put("task", t.id, t.to_dict())

    def save_product(self, p: M.Product) -> None:
        self.products[p.id] = p
        self.store.put("product", p.id, p.to_dict())

    def set(self, key: str, value: Any) -> None:
        """A persisted scalar (phase, team colour, counters, ...)."""
        self.meta[key] = value
        self.store.put("meta", key, value)

    def get(self, key: str, default: Any = None) -> Any:
        return self.meta.get(key, default)

    def next_id(self, counter: str) -> int:
        n = int(self.meta.get(counter, 0)) + 1
        self.set(counter, n)
        return n

    # -- queries -------------------------------------------------------------------
    def open_tasks(self) -> list[M.Task]:
        return [t for t in self.tasks.values() if t.state in M.OPEN_STATES]

    def tasks_of(self, ids: Iterable[int]) -> list[M.Task]:
        return [self.tasks[i] for i in ids if i in self.tasks]

    def active_robots(self) -> list[M.Robot]:
        """The active robots by number: the order the robots registered in (which agent process
        connected first, in a process game) must not change whom the dispatcher serves first."""
        return sorted((r for r in self.robots.values() if r.status == M.ACTIVE), key=lambda r: r.number)
