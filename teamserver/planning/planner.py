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
"""
from __future__ import annotations

from dataclasses import dataclass, field

from rll_bt.clock import Clock, WallClock
from rll_bt.rules import Profile

from .. import model as M
from .domain import DOMAIN, ProductionContext, Progress
from .estimate import Durations, SimRobot, SimTask, simulate
from .htn import Network, Planner, PlanningFailed


@dataclass
class Candidate:
    """One unit of an order that could be started now."""

    order: M.Order
    network: Network
    key: str                         # product id it would get


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

    @property
    def slots(self) -> int:
        """How many more products may be started now."""
        making = sum(self.in_progress.values()) if self.making is None else self.making
        return max(self.max_products - making, 0)


@dataclass
class Choice:
    """Result of :meth:`ProductionPlanner.choose`."""

    start: list[Candidate]
    points: int
    baseline_points: int
    evaluations: int
    candidates: int


class ProductionPlanner:
    def __init__(self, profile: Profile, team_prefix: str, *, durations: Durations = Durations(),
                 budget: float = 0.04, max_evaluations: int = 60, clock: Clock | None = None,
                 max_expansions: int = 5000):
        self.profile = profile
        self.prefix = team_prefix
        self.durations = durations
        self.budget = budget
        self.max_evaluations = max_evaluations
        self.clock = clock if clock is not None else WallClock()
        self.htn = Planner(DOMAIN, max_expansions=max_expansions)

    # -- one product ---------------------------------------------------------
    def context(self, world: World, order: M.Order, progress: Progress | None = None
                ) -> ProductionContext:
        return ProductionContext(self.prefix, world.rs_colors, world.ring_costs, world.cs_caps,
                                 order, progress or Progress(), world.unusable,
                                 ds_by_order=self.profile.year >= 2017)

    def decompose(self, ctx: ProductionContext) -> Network:
        """The task network for ``ctx.order``; raises :class:`PlanningFailed`."""
        return self.htn.plan(ctx, ("product",))

    # -- which orders ----------------------------------------------------------
    def candidates(self, world: World) -> list[Candidate]:
        out = []
        for o in sorted(world.orders, key=lambda o: (o.end, o.id)):
            units = o.open - world.in_progress.get(o.id, 0)
            if units <= 0 or o.end + self.profile.scoring.delivery_late_grace <= world.now:
                continue
            try:
                net = self.decompose(self.context(world, o))
            except PlanningFailed:
                continue
            for u in range(units):
                out.append(Candidate(o, net, f"cand-{o.id}-{u}"))
        return out

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
    deadline, no look-ahead."""

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
