"""Production planning: decompose orders, pick which to make, within a time budget.

:meth:`ProductionPlanner.decompose` turns one order (and what exists of its
product) into a task network with the HTN domain.  :meth:`ProductionPlanner.choose`
picks which candidate orders to start now, *anytime*: a greedy start by
deadline and value, then swaps, additions and removals, each candidate set
scored by simulating the whole plan (products in progress plus the new
ones) on the robots; the best set found when the budget runs out wins.
The budget is a wall-time limit measured on ``clock`` and a cap on
simulations, so in a lockstep run (a simulated clock) the result depends
only on the cap and the run stays deterministic.

With a storage station (rcll2025) a product expected ready long before its
order's window opens is stored there meanwhile (:class:`StoragePolicy`,
``docs/planning.md``): :meth:`ProductionPlanner.decompose` first plans the
direct hand-over, simulates it with the work in progress to estimate when the
product is ready, and plans again with that estimate.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

from rll_bt.clock import Clock, WallClock
from rll_bt.rules import Profile

from ..knowledge import model as M
from .domain import DOMAIN, ProductionContext, Progress, Storage, storage_pays
from .estimate import Durations, SimRobot, SimTask, simulate
from .htn import Network, Planner, PlanningFailed


@dataclass
class Candidate:
    """One unit of an order that could be started now (``stock``: the storage station's
    place of the product it hands over from the stock the game began with)."""

    order: M.Order
    network: Network
    key: str                         # product id it would get
    stock: tuple[int, int] | None = None


@dataclass
class World:
    """A snapshot for :meth:`ProductionPlanner.choose`.

    ``active``: steps of products in progress (done ones listed in ``done``);
    ``positions``: machine name -> (x, y); ``now``/``horizon``: production
    game time now and at its end; ``owned``: station locks held now;
    ``in_progress``: order id -> units being made or delivered but not yet
    counted by the refbox; ``making``: products being made (what
    ``max_products`` limits; a delivered product no longer takes a slot).
    """

    orders: list[M.Order]
    robots: list[SimRobot]
    positions: dict[str, tuple[float, float]]
    rs_colors: dict[str, tuple[str, ...]]
    ring_costs: dict[str, int]
    cs_caps: dict[str, str]
    now: float
    horizon: float
    active: list[SimTask] = field(default_factory=list)
    done: set = field(default_factory=set)
    owned: dict[str, str] = field(default_factory=dict)
    in_progress: dict[int, int] = field(default_factory=dict)   # order id -> products
    unusable: frozenset[str] = frozenset()
    max_products: int = 3
    making: int | None = None       # products being made (None: the sum of in_progress)
    # 2025: C0 products the storage station held at the start and still holds unclaimed:
    # (shelf, slot) -> (base, cap)
    stock: dict[tuple[int, int], tuple[str, str]] = field(default_factory=dict)

    @property
    def slots(self) -> int:
        """How many more products may be started now."""
        making = sum(self.in_progress.values()) if self.making is None else self.making
        return max(self.max_products - making, 0)


@dataclass(frozen=True)
class StoragePolicy:
    """When finished products go into the storage station (profiles that have one).

    A product expected ready ``min_wait`` s or more before its order's window
    opens is stored, where ``min_wait`` is what the detour costs robots
    (:meth:`ProductionPlanner.storage_cost`) plus ``margin`` (the estimate's
    slack, and the freed robot must find work) plus the points storing costs
    (2025: -5 to store, -5 to retrieve) at ``point_value`` points per second
    of a robot's time (a robot is worth about 0.08 points a second in
    production: 300 points of three robots in 1200 s).  ``retrieve_lead``: the
    retrieval starts this long before the window opens.  ``min_wait`` given:
    that threshold instead (-inf: store every product).  ``enabled`` False:
    never store (a product already stored is still retrieved).
    """

    enabled: bool = True
    margin: float = 30.0
    retrieve_lead: float = 45.0
    min_wait: float | None = None
    point_value: float = 0.08


@dataclass
class Choice:
    """Result of :meth:`ProductionPlanner.choose`."""

    start: list[Candidate]
    points: int
    baseline_points: int
    evaluations: int
    candidates: int


class ProductionPlanner:
    def __init__(self, profile: Profile, team_prefix: str, *, durations: Durations | None = None,
                 budget: float = 0.04, max_evaluations: int = 60, clock: Clock | None = None,
                 max_expansions: int = 5000, storage: StoragePolicy = StoragePolicy()):
        self.profile = profile
        self.storage = storage
        self.prefix = team_prefix
        self.durations = durations if durations is not None else Durations()
        self.budget = budget
        self.max_evaluations = max_evaluations
        self.clock = clock if clock is not None else WallClock()
        self.htn = Planner(DOMAIN, max_expansions=max_expansions)

    # -- one product ---------------------------------------------------------
    def context(self, world: World, order: M.Order, progress: Progress | None = None
                ) -> ProductionContext:
        return ProductionContext(self.prefix, world.rs_colors, world.ring_costs, world.cs_caps,
                                 order, progress or Progress(), world.unusable,
                                 ds_by_order=self.profile.year >= 2017,
                                 storage=self.storage_for(world))

    @property
    def ss(self) -> str | None:
        """Our storage station, None when the profile has none."""
        return f"{self.prefix}-SS" if "SS" in self.profile.machine_types else None

    def storage_for(self, world: World) -> Storage | None:
        """The storage station as the domain sees it (no ``ready_at`` yet)."""
        if self.ss is None:
            return None
        pol = self.storage
        if not pol.enabled:
            wait = math.inf
        elif pol.min_wait is not None:
            wait = pol.min_wait
        else:
            sc = self.profile.scoring
            fee = -(sc.ss_store + sc.ss_retrieve) / pol.point_value if pol.point_value > 0 else 0.0
            wait = self.storage_cost(world.positions) + pol.margin + max(fee, 0.0)
        return Storage(self.ss, wait, pol.retrieve_lead)

    def storage_cost(self, positions: dict[str, tuple[float, float]]) -> float:
        """Robot seconds the detour through the storage station costs beyond a direct
        delivery: a put and a pickup, driving cap station -> SS twice (the robot that
        retrieves comes from about there) and SS -> DS instead of cap station -> DS
        (averaged over our cap stations; 20 s of driving while positions are unknown)."""
        d = self.durations
        ss, ds = positions.get(self.ss), positions.get(f"{self.prefix}-DS")
        css = [positions[c] for c in sorted(positions) if c.startswith(f"{self.prefix}-CS")]
        if ss is None or ds is None or not css:
            drive = 20.0
        else:
            drive = sum(2 * math.dist(c, ss) + math.dist(ss, ds) - math.dist(c, ds)
                        for c in css) / len(css) / d.speed
        return d.put + d.pickup + max(drive, 0.0)

    def decompose(self, ctx: ProductionContext, world: World | None = None) -> Network:
        """The task network for ``ctx.order``; raises :class:`PlanningFailed`.  With a
        ``world`` and a storage station, the product's ready time is estimated from
        the direct plan (:meth:`ready_time`) and the storage steps are planned where
        they pay (``ctx.storage.ready_at`` given: that estimate is used as is)."""
        net = self.htn.plan(ctx, ("product",))
        st = ctx.storage
        if st is None or st.ready_at is not None or world is None or \
                ctx.order.begin - world.now < st.min_wait:
            return net                  # (it cannot be ready any earlier than now)
        ctx = replace(ctx, storage=replace(st, ready_at=self.ready_time(net, ctx.order, world)))
        return self.htn.plan(ctx, ("product",)) if storage_pays(ctx) else net

    def ready_time(self, net: Network, order: M.Order, world: World) -> float | None:
        """Game time the product of ``net`` (a direct hand-over) is expected in a gripper,
        finished: the work in progress and this product list-scheduled on the robots
        (None: not within the simulation)."""
        deliver = [i for i, s in enumerate(net.steps) if s.fields["kind"] == M.DELIVER]
        if not deliver:
            return None
        before = net.predecessors(deliver[0])
        if not before:
            return world.now                     # in a gripper already
        tasks = list(world.active) + sim_tasks(net, "ready?", order)
        r = simulate(self.profile, tasks, world.robots, world.positions, world.now,
                     math.inf, self.durations, world.done, world.owned)
        return r.finish.get(("ready?", before[0]))

    # -- which orders ----------------------------------------------------------
    def candidates(self, world: World) -> list[Candidate]:
        """A candidate per open unit of every order still worth making; a C0 whose base and
        cap the storage station's stock has is handed over from there (retrieve, -5, and
        deliver) instead of being made."""
        out = []
        stock = dict(world.stock)
        for o in sorted(world.orders, key=lambda o: (o.end, o.id)):
            units = o.open - world.in_progress.get(o.id, 0)
            sc = self.profile.scoring
            if units <= 0 or (not sc.delivery_late_steps
                              and o.end + sc.delivery_late_grace <= world.now):
                continue                # (2025: a late delivery still pays, graded)
            made = None                  # the network that makes one (planned once)
            for u in range(units):
                place = self._from_stock(o, stock)
                try:
                    if place is not None:
                        net = self.decompose(self.context(world, o, Progress(
                            base=o.base, cap=o.cap, location=f"{self.ss}:{M.SHELF}",
                            stored_at=place)), world)
                    else:
                        made = made or self.decompose(self.context(world, o), world)
                        net = made
                except PlanningFailed:
                    continue
                if place is not None:
                    del stock[place]
                out.append(Candidate(o, net, f"cand-{o.id}-{u}", place))
        return out

    def _from_stock(self, order: M.Order, stock: dict) -> tuple[int, int] | None:
        if order.complexity != 0 or order.rings:
            return None
        return next((pl for pl, (b, c) in sorted(stock.items())
                     if b == order.base and c == order.cap), None)

    def choose(self, world: World) -> Choice:
        """The candidate orders to start now (see the module doc)."""
        t0 = self.clock.now()
        cands = self.candidates(world)
        slots = world.slots
        evals = 0

        def score(chosen: tuple[int, ...]) -> tuple[int, float]:
            nonlocal evals
            evals += 1
            tasks = list(world.active)
            for i in chosen:
                tasks += sim_tasks(cands[i].network, cands[i].key, cands[i].order)
            r = simulate(self.profile, tasks, world.robots, world.positions, world.now,
                         world.horizon, self.durations, world.done, world.owned)
            return r.points, -r.makespan

        def out_of_budget() -> bool:
            return (evals >= self.max_evaluations
                    or self.clock.now() - t0 >= self.budget)

        base = score(())
        best, best_score = (), base
        if slots and cands:
            # greedy: earliest deadline first, keep what adds points
            for i in range(len(cands)):
                if len(best) >= slots or out_of_budget():
                    break
                trial = best + (i,)
                s = score(trial)
                if s > best_score:
                    best, best_score = trial, s
            # local search: swap one in for one out, then try removals
            improved = True
            while improved and not out_of_budget():
                improved = False
                outside = [i for i in range(len(cands)) if i not in best]
                moves = [tuple(x for x in best if x != j) + (i,) for j in best for i in outside]
                moves += [tuple(x for x in best if x != j) for j in best]
                if len(best) < slots:
                    moves += [best + (i,) for i in outside]
                for trial in moves:
                    if out_of_budget():
                        break
                    s = score(trial)
                    if s > best_score:
                        best, best_score, improved = trial, s, True
                        break
        return Choice([cands[i] for i in sorted(best)], best_score[0], base[0], evals, len(cands))


def sim_tasks(net: Network, product: str, order: M.Order | None,
              done_holder: dict | None = None) -> list[SimTask]:
    """The network's steps as :class:`SimTask` (keys ``(product, index)``)."""
    out = []
    for i, st in enumerate(net.steps):
        f = st.fields
        out.append(SimTask(
            key=(product, i), product=product, kind=f["kind"],
            machine=f["params"].get("machine"), params=f["params"],
            deps=tuple((product, j) for j in net.predecessors(i)),
            locks=f["locks"], releases=f["releases"], carry=f["carry"], holder=f["holder"],
            not_before=float(f["params"].get("not_before", 0.0)), order=order))
    return out


class GreedyPlanner(ProductionPlanner):
    """The baseline: one product at a time, for the plannable order with the earliest
    deadline, no look-ahead (so nothing stored for later either)."""

    def __init__(self, profile: Profile, team_prefix: str, **options):
        options.setdefault("storage", StoragePolicy(enabled=False))
        super().__init__(profile, team_prefix, **options)

    def choose(self, world: World) -> Choice:
        if sum(world.in_progress.values()) > 0 or not world.slots:
            return Choice([], 0, 0, 0, 0)
        cands = self.candidates(world)
        return Choice(cands[:1], 0, 0, 0, len(cands))


#: the team server's production planners by name (``ServerConfig.planner``)
PLANNERS = {"htn": ProductionPlanner, "greedy": GreedyPlanner}


def make_planner(name: str, profile: Profile, team_prefix: str, **options) -> ProductionPlanner:
    """The planner called ``name`` (one of :data:`PLANNERS`)."""
    try:
        cls = PLANNERS[name]
    except KeyError:
        raise ValueError(f"unknown planner {name!r} (one of {', '.join(PLANNERS)})") from None
    return cls(profile, team_prefix, **options)
