"""Robots left holding a workpiece they cannot use yet.

A robot that picks up a workpiece whose next step is not ready (the other
parts of the step are still missing, or the order's window is not open)
is *stuck* with it: it can do nothing else until the step is ready.  When
every robot is stuck, nobody fetches the missing parts and production
stops (seed 7 of the rcll2016 benchmark stopped this way for its last
420 s).  :class:`Holding` tells which pickups would leave their robot
stuck (:meth:`~Holding.blocks`), how many robots are stuck
(:meth:`~Holding.stuck`) and how many may be (:meth:`~Holding.hold_limit`),
and which tasks free a stuck robot (:meth:`~Holding.unblocking`).

A new base whose next step also waits for a step that nobody does or can
start now (a cap retrieval at a station still holding another cap, a base for
the slide that waits for such a retrieval) is not fetched at all
(:meth:`~Holding.premature`): its robot would hold it for as long as that
other work takes.  And a pickup that leaves its robot holding costs
``hold_cost`` metres in the matching, so that of two pickups at one BS the
base for a slide (put at once) goes before the product's own base.  (rcll2025
seed 6 with 20 % loss: robots held new bases 559-587 s in all, against 253-291 s
in the clean game; most of it waits for a busy ring or cap station, which
these rules leave as it was.  Production with them, benchmarks/README.md:
rcll2025 seeds 1-10 mean 551.0 against 513.7, rcll2016 20 seeds 312.8
against 315.9, its lowest 217 against 157.)

A pickup that clears a station's output for a stuck robot
(:meth:`~Holding.swaps`) leaves its own robot holding, but the stuck one goes
on at once: no more robots are stuck after it, so the limit does not hold it
back.  Held back, the other product's workpiece stayed in the output and the
stuck robot's step waited for that station for the rest of the game
(rcll2025 seed 18: from 380 s, all three robots holding).
"""
from __future__ import annotations

from ..knowledge import model as M
from ..knowledge.kb import KnowledgeBase
from ..production.feeding import FeedMonitor
from ..production.locks import StationLocks
from .config import DispatchConfig
from .fleet import next_task
from .readiness import Readiness


class Holding:
    """See the module doc."""

    def __init__(self, kb: KnowledgeBase, readiness: Readiness, locks: StationLocks,
                 feeds: FeedMonitor, config: DispatchConfig):
        self.kb = kb
        self.readiness = readiness
        self.locks = locks
        self.feeds = feeds
        self.config = config

    @staticmethod
    def hold_limit(task: M.Task, robots: int) -> int:
        """How many robots may be left holding what they cannot use yet, counting the
        one taking ``task``: one fewer than the robots for a pickup that clears a
        station's output; two fewer (but one of two) for a new base from the BS:
        it only starts work, and a robot fetching parts must stay free besides
        the one clearing outputs."""
        if (task.machine or "").endswith("-BS"):
            return max(robots - 2, min(robots - 1, 1))
        return robots - 1

    def blocks(self, task: M.Task, game_time: float | None) -> bool:
        """Would the robot that picks up ``task``'s workpiece be left holding it, its
        next step not ready (other parts missing, the order's window not open)?"""
        nxt = self._carry_after(task)
        return nxt is not None and not self._ready_once_held(nxt, game_time, task.id)

    def premature(self, task: M.Task, game_time: float | None) -> bool:
        """Is ``task`` a pickup of a new base from the BS whose next step also waits
        for a step that nobody does or can start now (see the module doc)?"""
        if not (task.machine or "").endswith("-BS"):
            return False
        nxt = self._carry_after(task)
        if nxt is None:
            return False
        slides = self.readiness.slides          # a ring whose slide holds its cost needs not its own bases
        stocked = nxt.kind == M.MOUNT_RING and slides.stocked_for(nxt)
        return not all(self._under_way(d, game_time, {task.id})
                       or stocked and slides.own_base(self.kb.tasks.get(d), nxt) for d in nxt.deps)

    def _under_way(self, tid: int, game_time: float | None, seen: set[int]) -> bool:
        """Is task ``tid`` done, running, ready to go, or waiting only for steps that are?"""
        t = self.kb.tasks.get(tid)
        if tid in seen or t is None or t.state != M.PENDING:
            return True
        if self.readiness.ready(t, game_time):
            return True
        seen.add(tid)
        open_deps = [d for d in t.deps if (dep := self.kb.tasks.get(d)) is not None and dep.state != M.DONE]
        # waiting for nothing but its own conditions (a busy station, a cap not due): nobody can start it
        return bool(open_deps) and all(self._under_way(d, game_time, seen) for d in open_deps)

    def _carry_after(self, task: M.Task) -> M.Task | None:
        """The pending step that carries on what pickup ``task`` takes (None if it is
        not a pickup, or nothing waits for it)."""
        if task.kind != M.GET_WORKPIECE or task.carry or task.product is None:
            return None
        product = self.kb.products.get(task.product)
        nxt = [t for t in self.kb.tasks_of(product.tasks if product else ())
               if t.state == M.PENDING and t.carry and t.params.get("carry_from") == task.id]
        return nxt[0] if nxt else None

    def _ready_once_held(self, task: M.Task, game_time: float | None, pickup: int) -> bool:
        """Would carry ``task`` be ready right after its ``pickup`` (a task id)?"""
        if game_time is None:
            return False
        for d in task.deps:
            dep = self.kb.tasks.get(d)
            if d != pickup and (dep is None or dep.state != M.DONE):
                return False
        if not (self.locks.free_for(task) and self.readiness.station_usable(task.machine)
                and self.feeds.accepts(task)):
            return False
        if task.kind == M.PUT_WORKPIECE and not self.readiness.slides.slide_ready(task):
            return False                # a slide without room for the base
        if task.kind == M.DELIVER:
            return game_time + self.config.pickup_time >= self.readiness.deliver_from(task)
        return True

    def _next_carries(self) -> dict[int, M.Task]:
        """Robot number -> the pending step that carries what it holds."""
        return {t.holder: t for t in self.kb.open_tasks()
                if t.carry and t.state == M.PENDING and t.holder is not None}

    def stuck(self, game_time: float | None) -> int:
        """Robots holding a workpiece whose next step is not ready, or on their way to
        pick up one (see :meth:`blocks`)."""
        bound = self._next_carries()
        n = 0
        for r in self.kb.active_robots():
            t = next_task(self.kb, r)          # (a pickup queued behind a put: it will hold that)
            if t is not None and t.state == M.ASSIGNED and t.kind != M.GO_TO:
                n += self.blocks(t, game_time)
            elif r.holding and r.number in bound:
                n += not self.readiness.ready(bound[r.number], game_time)
        return n

    def unblocking(self, game_time: float | None) -> set[int]:
        """Pending tasks the next step of a stuck robot waits for (its predecessors,
        transitively): doing them frees that robot, so they go first.  A robot on
        its way to a pickup that will leave it stuck (:meth:`blocks`) counts too: a
        product whose last ring is mounted waits for its cap, and the cap's
        retrieval started while it is being fetched saves that wait (rcll2025 seed
        2 with 20 % loss: a robot held a product 100 s while another fetched a
        base for a later product)."""
        bound = self._next_carries()
        out: set[int] = set()
        for r in self.kb.active_robots():
            nxt = bound.get(r.number) if r.holding else None
            if nxt is None:
                t = next_task(self.kb, r)
                if t is not None and t.state == M.ASSIGNED and self.blocks(t, game_time):
                    nxt = self._carry_after(t)
            elif self.readiness.ready(nxt, game_time):
                nxt = None
            if nxt is None:
                continue
            todo = list(nxt.deps)
            while todo:
                d = todo.pop()
                t = self.kb.tasks.get(d)
                if t is not None and t.state == M.PENDING and d not in out:
                    out.add(d)
                    todo.extend(t.deps)
        return out

    def swaps(self, game_time: float | None) -> set[int]:
        """Pending pickups that give up the station locks another product holds, for
        which alone the next step of a stuck robot waits (that product's workpiece
        in the station's output): taking one frees the stuck robot."""
        bound = self._next_carries()
        owners = self.locks.owners
        out: set[int] = set()
        for r in self.kb.active_robots():
            nxt = bound.get(r.number) if r.holding else None
            if nxt is None or self.readiness.ready(nxt, game_time):
                continue
            for other in {owners[lk] for lk in nxt.locks if owners.get(lk, nxt.product) != nxt.product}:
                theirs = {lk for lk in nxt.locks if owners.get(lk) == other}
                product = self.kb.products.get(other)
                if product is None or not self.readiness.ready(nxt, game_time, but=other):
                    continue
                out |= {t.id for t in self.kb.tasks_of(product.tasks)
                        if t.kind == M.GET_WORKPIECE and not t.carry and t.state == M.PENDING
                        and theirs <= set(t.releases)}
        return out
