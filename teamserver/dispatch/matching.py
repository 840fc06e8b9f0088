"""Ready tasks to available robots.

Carry tasks go to the robot holding the workpiece; the others are matched
to idle robots with empty grippers by travel distance plus ``urgency``
times the seconds left until the order's window closes (an optimal
assignment, ``scipy.optimize.linear_sum_assignment``), earlier products
first on ties; tasks that free a stuck robot are preferred by ``unblock``
metres, and the steps of a product whose retrieved cap waits in a cap
station by ``cap_first`` metres (the cap keeps that station from every
other product until it is mounted), and a product's due cap retrieval (its
rings under way: the product waits for that cap next) by ``cap_due``.  A robot
on its way to a pickup that will leave it stuck counts as stuck.  Pickups that
would leave one more robot stuck wait while ``robots - 1`` are
(:mod:`.holding`), but a pickup that frees a stuck robot by clearing its
station's output; a new base whose next step waits for work nobody can start
yet is not fetched (:meth:`Holding.premature`), and a pickup that leaves its robot
holding costs ``hold_cost`` metres more; when all are stuck, a base held for a full slide goes to
another slide.  Locks are taken at assignment.  A robot about to finish a task
that leaves its gripper empty, near that task's station, is matched as it will
be (there, empty: :meth:`Fleet.finishing`) and the task it gets is queued behind
its current one: on a radio with 2 s of delay the result's way up and the next
task's way down cost 4 s between any two tasks (benchmarks/README.md).
"""
from __future__ import annotations

import numpy as np
from scipy.optimize import linear_sum_assignment

from ..knowledge import model as M
from ..knowledge.kb import KnowledgeBase
from ..production.caps import FREE, Caps
from ..production.locks import StationLocks
from ..production.products import CLEANUP_ORDER
from ..production.slides import Slides
from ..production.world import PlanningWorld
from .config import DispatchConfig
from .fleet import Fleet, travel
from .holding import Holding
from .readiness import Readiness


class Matcher:
    """See the module doc."""

    def __init__(self, kb: KnowledgeBase, fleet: Fleet, readiness: Readiness, holding: Holding,
                 locks: StationLocks, caps: Caps, slides: Slides, world: PlanningWorld,
                 config: DispatchConfig):
        self.kb = kb
        self.fleet = fleet
        self.readiness = readiness
        self.holding = holding
        self.locks = locks
        self.caps = caps
        self.slides = slides
        self.world = world
        self.config = config
        self._all_stuck_since: float | None = None

    def assign(self, game_time: float | None) -> list[M.Task]:
        """Give ready tasks to idle robots; returns the tasks assigned now."""
        idle = {r.number: r for r in self.fleet.available_robots()}
        if not idle and self.config.queue_near is None:
            return []
        self.caps.adopt_free_caps()
        self.slides.top_up_slides()
        self.slides.waive_stocked_puts()
        self.slides.waive_full_slide_puts()
        if self._all_stuck_for(game_time) >= self.config.divert_after:
            for t in self.kb.open_tasks():  # a base for a full slide goes elsewhere
                r = idle.get(t.holder) if t.carry and t.holder is not None else None
                if r is not None and self.slides.divert(t, r, self._travel):
                    break
        ready = [t for t in self.kb.open_tasks() if self.readiness.ready(t, game_time)]
        assigned: list[M.Task] = self._queue_carries(game_time)
        # carry tasks: their holder, if idle
        for t in sorted(ready, key=lambda t: t.id):
            if t.carry:
                r = idle.get(t.holder) if t.holder is not None else None
                # (slide room again: a put assigned a moment ago in this loop took the last place)
                if r is not None and self.locks.free_for(t) and self.slides.slide_ready(t):
                    self.slides.discard_to(t, r, self._travel)
                    self.fleet.assign(t, r)
                    assigned.append(t)
                    del idle[r.number]
        if self.config.queue_near is not None:       # robots about to finish, as they will be
            idle.update((r.number, r) for r in self.fleet.finishing(self.world.positions(), self.config.queue_near))
        free = [r for r in idle.values() if not r.holding]
        pool = [t for t in ready if not t.carry]
        if not free or not pool:
            return assigned
        # robots must stay able to fetch what the held workpieces wait for
        stuck, n = self.holding.stuck(game_time), len(self.kb.active_robots())
        swaps = self.holding.swaps(game_time) if stuck else set()    # (take one, free one)
        blocking = {t.id: self.holding.hold_limit(t, n) for t in pool
                    if t.id not in swaps and self.holding.blocks(t, game_time)}
        pool = [t for t in pool if stuck < blocking.get(t.id, n)
                and (self.config.fetch_early or t.id not in blocking
                     or not self.holding.premature(t, game_time))]
        if not pool:
            return assigned
        positions = self.world.positions()
        frees = (self.holding.unblocking(game_time) | swaps) if stuck else set()
        capped = {p for p in self.caps.buffers.owners.values() if p != FREE}
        cost = np.zeros((len(free), len(pool)))
        for i, r in enumerate(free):
            for j, t in enumerate(pool):
                cost[i, j] = (travel(r, positions.get(t.machine)) + 1e-3 * _age(t)
                              + self.config.urgency * self._slack(t, game_time)
                              - self.config.unblock * (t.id in frees)
                              - self.config.cap_first * (t.product in capped)
                              - self.config.cap_due * self._cap_due(t)
                              + self.config.hold_cost * (t.id in blocking))
        rows, cols = linear_sum_assignment(cost)
        for i, j in sorted(zip(rows, cols), key=lambda ij: cost[ij[0], ij[1]]):
            t, r = pool[j], free[i]
            if not self.locks.free_for(t) or not self.slides.slide_ready(t):
                continue                    # another assignment just took the station or the slide's room
            if t.id in blocking:
                if stuck >= blocking[t.id]:
                    continue                # the next tick matches this robot anew
                stuck += 1
            self.fleet.assign(t, r)
            assigned.append(t)
        return assigned

    def _queue_carries(self, game_time: float | None) -> list[M.Task]:
        """The step that carries what a robot near the end of a pickup will hold, ready
        but for that pickup, queued behind it (it goes to that robot anyway)."""
        if self.config.queue_near is None:
            return []
        out = []
        for r, pickup in self.fleet.near_the_end(self.world.positions(), self.config.queue_near):
            if pickup.kind != M.GET_WORKPIECE:
                continue
            c = next((t for t in self.kb.open_tasks() if t.carry and t.state == M.PENDING
                      and t.params.get("carry_from") == pickup.id and t.kind != M.DISCARD), None)
            if c is not None and self.readiness.ready(c, game_time, done=(pickup.id,)) \
                    and self.locks.free_for(c) and self.slides.slide_ready(c):
                self.fleet.queue(c, r)
                out.append(c)
        return out

    def _all_stuck_for(self, game_time: float | None) -> float:
        """Seconds every robot has been stuck (:meth:`Holding.stuck`) without work (a
        robot on its way to a pickup may be about to free another), 0 if not all are."""
        now = self.fleet.clock.now()
        robots, idle = self.kb.active_robots(), {r.number for r in self.fleet.available_robots()}
        if (any(r.number not in idle for r in robots)
                or self.holding.stuck(game_time) < len(robots)):
            self._all_stuck_since = None
            return 0.0
        if self._all_stuck_since is None:
            self._all_stuck_since = now
        return now - self._all_stuck_since

    def _cap_due(self, task: M.Task) -> bool:
        """Is ``task`` a product's cap retrieval whose rings are under way?  (A ready
        RETRIEVE_CAP is due, :meth:`Caps.cap_due`.)  The product waits for that cap
        next: its retrieval is on the product's critical path."""
        if task.kind != M.RETRIEVE_CAP:
            return False
        p = self.kb.products.get(task.product or "")
        return p is not None and p.order_id != CLEANUP_ORDER

    def _travel(self, robot: M.Robot, machine: str) -> float:
        return travel(robot, self.world.positions().get(machine))

    def _slack(self, task: M.Task, game_time: float | None) -> float:
        """Game seconds until the end of the window of ``task``'s order (0 for work
        that only clears a station: it goes first)."""
        p = self.kb.products.get(task.product or "")
        o = self.kb.orders.get(p.order_id) if p is not None else None
        if o is None or game_time is None:
            return 0.0
        return min(max(o.end - game_time, 0.0), float(self.kb.profile.phases.production))


def _age(task: M.Task) -> float:
    return float(task.id)
