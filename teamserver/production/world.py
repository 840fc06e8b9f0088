"""The planning world: what the production planner is given at a planning round.

:class:`PlanningWorld` builds a :class:`~teamserver.planning.planner.World`
from the knowledge base: open orders, the robots and where they are, our
stations' best known positions, ring station colours and ring costs, the
cap stations' caps, the steps of the products under way (so that a new
product is scheduled around them), the station locks, the places the
robots keep failing at (:mod:`.health`) and how many products may be made
at once.
"""
from __future__ import annotations

from rll_bt.rules import CYAN, MAGENTA, Profile

from ..knowledge import model as M
from ..knowledge.kb import KnowledgeBase
from ..planning.estimate import SimRobot, SimTask
from ..planning.planner import ProductionPlanner, World
from .health import StationHealth
from .locks import StationLocks
from .products import CLEANUP_ORDER, DELIVERED, Products
from .shelves import CapShelves
from .storage import Shelf


class PlanningWorld:
    """See the module doc.  ``max_products``: products at once (None: one per
    robot); ``confirm_time``: game seconds a delivery of ours may wait for the
    refbox to count it before its unit is open again."""

    def __init__(self, kb: KnowledgeBase, planner: ProductionPlanner, products: Products,
                 locks: StationLocks, shelf: Shelf, health: StationHealth, *, prefix: str,
                 cs_caps: dict[str, str], clock=None, max_products: int | None = None,
                 confirm_time: float = 20.0, cap_shelves: CapShelves | None = None):
        self.kb = kb
        self.profile: Profile = kb.profile
        self.planner = planner
        self.products = products
        self.locks = locks
        self.shelf = shelf
        self.health = health
        self.prefix = prefix
        self.cs_caps = cs_caps
        self.clock = clock
        self.max_products = max_products
        self.confirm_time = confirm_time
        self.cap_shelves = cap_shelves
        self._positions: tuple | None = None     # (what they were computed from, positions)

    def unusable(self) -> frozenset[str]:
        """Places the robots keep failing at (see :mod:`teamserver.production.health`), and
        ``"<CS>:SHELF"`` for a cap station whose shelf is dry (:mod:`.shelves`), ``"<RS>:SLIDE"``
        for a ring station whose slide a wall leaves no room in front of (:mod:`.reach`)."""
        out = self.health.unusable(self.clock.now()) if self.clock is not None else frozenset()
        if self.cap_shelves is not None:
            out |= {f"{cs}:{M.SHELF}" for cs in self.cs_caps if self.cap_shelves.dry(cs)}
            out |= {f"{rs}:{M.SLIDE}" for rs in self.rs_colors() if self.cap_shelves.reach.slide_walled(rs)}
        return out

    def rs_colors(self) -> dict[str, tuple[str, ...]]:
        out = {}
        for kind in self.profile.machine_types:
            if not kind.startswith("RS"):
                continue
            name = f"{self.prefix}-{kind}"
            st = self.kb.stations.get(name)
            if st is not None and st.ring_colors:
                out[name] = tuple(st.ring_colors)
            elif self.profile.rs_colors is not None:
                out[name] = tuple(self.profile.rs_colors[kind])
        return out

    def positions(self) -> dict[str, tuple[float, float]]:
        """Our machines' best known positions (recomputed when observations or station
        records changed)."""
        key = (self.kb.observation_count, tuple((n, s.zone) for n, s in
                                                sorted(self.kb.stations.items())))
        if self._positions is not None and self._positions[0] == key:
            return dict(self._positions[1])
        out = {}
        for kind in self.profile.machine_types:
            name = f"{self.prefix}-{kind}"
            pos = self.kb.machine_position(name)
            if pos is not None:
                out[name] = pos
        self._positions = (key, out)
        return dict(out)

    def unconfirmed(self, game_time: float) -> dict[int, int]:
        """Order id -> our deliveries the refbox has not counted yet, of those made less
        than ``confirm_time`` game seconds ago.  An older one it never counted did not
        reach it (the workpiece was lost, or judged for no order): its unit is open again."""
        delivered: dict[int, int] = {}
        recent: dict[int, int] = {}
        for p in self.kb.products.values():
            if p.state == DELIVERED and p.order_id != CLEANUP_ORDER:
                delivered[p.order_id] = delivered.get(p.order_id, 0) + 1
                if p.delivered_at is None or game_time - p.delivered_at <= self.confirm_time:
                    recent[p.order_id] = recent.get(p.order_id, 0) + 1
        out = {}
        for oid, n in recent.items():
            o = self.kb.orders.get(oid)
            if o is not None and delivered[oid] > o.delivered:
                out[oid] = min(n, delivered[oid] - o.delivered)
        return out

    def build(self, game_time: float, horizon: float, exclude: str | None = None) -> World:
        """The planning world now (``exclude``: a product whose tasks are left out, the
        one being planned again)."""
        orders = [o for o in self.kb.orders.values() if o.open > 0]
        in_progress = self.unconfirmed(game_time)
        making = 0
        active, done = [], set()
        for p in self.products.active():
            in_progress[p.order_id] = in_progress.get(p.order_id, 0) + 1
            making += p.order_id != CLEANUP_ORDER
            if p.id == exclude:
                continue
            order = self.kb.orders.get(p.order_id)
            for t in self.kb.tasks_of(p.tasks):
                if t.state == M.CANCELLED or t.state == M.FAILED:
                    continue
                if t.state == M.DONE:
                    done.add(t.id)
                holder = t.holder if t.holder is not None else (
                    t.robot if t.state == M.ASSIGNED else None)
                active.append(SimTask(
                    key=t.id, product=p.id, kind=t.kind, machine=t.machine, params=t.params,
                    deps=t.deps, locks=t.locks, releases=t.releases, carry=t.carry,
                    holder=None if holder is None else str(holder),
                    not_before=float(t.params.get("not_before", 0.0)), order=order))
        robots = []
        for r in self.kb.active_robots():
            pos = (r.pose[0], r.pose[1]) if r.pose else self.start_position()
            robots.append(SimRobot(str(r.number), pos, game_time))
        n = self.max_products if self.max_products is not None else max(len(robots), 1)
        unusable = self.unusable()
        if self.planner.ss is not None and not self.shelf.storage_open():
            unusable |= {self.planner.ss}
        return World(orders, robots, self.positions(), self.rs_colors(),
                     dict(self.kb.get("ring_costs") or {}), self.cs_caps, game_time, horizon,
                     active=active, done=done, owned=self.locks.owners, in_progress=in_progress,
                     unusable=unusable, max_products=n, making=making,
                     stock=self.stock() if self.planner.ss not in unusable else {})

    def stock(self) -> dict[tuple[int, int], tuple[str, str]]:
        """C0 products in our storage station that no product of ours claimed (2025: the
        game begins with one of every base x cap there): the places the refbox reports
        filled with a description "BASE_... CAP_..." (MachineInfo ``status_ss``)."""
        ss = self.kb.stations.get(self.planner.ss or "")
        if ss is None:
            return {}
        taken = set(self.shelf.places)
        out = {}
        for entry in ss.stored:
            key, _, desc = entry.partition("=")
            words = desc.split()
            if key in taken or len(words) != 2 or not words[0].startswith("BASE_") or \
                    not words[1].startswith("CAP_"):
                continue
            shelf, slot = (int(v) for v in key.split(","))
            out[(shelf, slot)] = (words[0], words[1])
        return out

    def start_position(self) -> tuple[float, float]:
        """Where our robots enter the field (a robot whose pose is not known yet)."""
        team = CYAN if self.prefix == "C" else MAGENTA
        rect = self.profile.insertion.get(team)
        return rect.centre if rect else (0.0, 0.0)

    def ready_to_plan(self) -> bool:
        """Ring costs and RS colours are known (needed by every ring method)."""
        return bool(self.kb.get("ring_costs")) and bool(self.rs_colors())
