"""Caps: the cap stations' buffers, caps retrieved ahead, and when a cap is due.

A cap station holds at most one retrieved cap; while it does it cannot
retrieve another, and the product the cap is for keeps the station (its
``#cap`` lock) until the cap is mounted.  So

- a product retrieves its cap only when it is *due* (:meth:`Caps.cap_due`):
  once every ring mount that does not wait for the cap-less base is under
  way;
- an idle cap station gets a cap *ahead* (:meth:`Caps.prefill`) while
  robots have nothing else to do (more idle robots than steps that could
  start, or a robot left without work for a while: the dispatcher's
  ``idle_prefill``), also one whose planned products' caps are not due yet;
  it is *free* (owner :data:`FREE`), and the most urgent product whose cap
  is due there takes it instead of retrieving one
  (:meth:`Caps.adopt_free_caps`); a cap ahead no robot has taken yet gives
  way to a product whose cap became due there (:meth:`Caps.yield_prefills`).

:class:`CapBuffers` keeps who owns the cap each station holds, in the
knowledge base (``cap_buffer``: CS -> product id or :data:`FREE`).
"""
from __future__ import annotations

import logging

from ..knowledge import model as M
from ..knowledge.kb import KnowledgeBase
from ..planning.domain import CAPLESS, EXTRA, ProductionContext
from ..planning.htn import Seq
from ..planning.planner import ProductionPlanner
from .locks import StationLocks
from .products import ABANDONED, CLEANUP_ORDER, Products
from .shelves import CapShelves
from .world import PlanningWorld

log = logging.getLogger("teamserver.production")

FREE = "free"              # owner of a retrieved cap no product owns yet (cap_buffer)


class CapBuffers:
    """CS -> the product whose retrieved cap it holds (or :data:`FREE`)."""

    def __init__(self, kb: KnowledgeBase):
        self.kb = kb

    @property
    def owners(self) -> dict[str, str]:
        """CS -> owner of the cap it holds (a copy)."""
        return dict(self.kb.get("cap_buffer", {}))

    def set(self, buf: dict[str, str]) -> None:
        self.kb.set("cap_buffer", buf)

    def take(self, cs: str, product_id: str) -> None:
        """``cs`` holds a cap for ``product_id`` (or :data:`FREE`)."""
        buf = self.owners
        buf[cs] = product_id
        self.set(buf)


class Caps:
    """When caps are retrieved, and caps retrieved ahead (see the module doc).
    ``prefill``: retrieve caps ahead at all; ``prefill_stop``: not this close
    (s) to the end; ``prefill_unknown``: until this game time also a colour
    no order wants yet."""

    def __init__(self, kb: KnowledgeBase, buffers: CapBuffers, products: Products,
                 planner: ProductionPlanner, world: PlanningWorld, locks: StationLocks,
                 shelves: CapShelves, *, prefix: str, cs_caps: dict[str, str], prefill: bool = True,
                 prefill_stop: float = 120.0, prefill_unknown: float = 600.0):
        self.kb = kb
        self.buffers = buffers
        self.products = products
        self.planner = planner
        self.world = world
        self.locks = locks
        self.shelves = shelves
        self.prefix = prefix
        self.cs_caps = cs_caps
        self.prefill_caps = prefill
        self.prefill_stop = prefill_stop
        self.prefill_unknown = prefill_unknown

    def adopt_free_caps(self) -> list[M.Product]:
        """Give each cap retrieved ahead (or left by an abandoned product) to the most
        urgent product whose cap retrieval there is due (:meth:`cap_due`): its cap
        chain (retrieve, take the cap-less base, discard it or put it on a slide) is
        cancelled, a base from the BS takes the cap-less base's place on the slide.
        (A station holding a cap cannot retrieve another: without this the product
        would wait for ever.)"""
        self.yield_prefills()
        out = []
        for cs, owner in sorted(self.buffers.owners.items()):
            if owner != FREE:
                continue
            best = None
            for p in self.products.active():
                order = self.kb.orders.get(p.order_id)
                if order is None:
                    continue
                chain = self.cap_chain(p, cs)
                if chain is None or not self.cap_due(chain[0]):
                    continue                    # it would keep the cap long unmounted
                if best is None or order.end < best[0]:
                    best = (order.end, p, chain)
            if best is None:
                continue
            _, p, (retrieve, pickup, after) = best
            for t in (retrieve, pickup) + ((after,) if after.kind == M.DISCARD else ()):
                t.state, t.error = M.CANCELLED, f"mounts the cap waiting in {cs}"
                self.kb.save_task(t)
            for t in self.kb.tasks_of(p.tasks):     # a waived mount waited for the pickup
                if t.id != after.id and pickup.id in t.deps:
                    t.deps = tuple(d for d in t.deps if d != pickup.id)
                    self.kb.save_task(t)
            if after.kind == M.DISCARD:
                for t in self.kb.tasks_of(p.tasks):
                    if after.id in t.deps:
                        t.deps = tuple(d for d in t.deps if d != after.id)
                        self.kb.save_task(t)
            else:                               # the slide still wants a base: from the BS
                bs = f"{self.prefix}-BS"
                base = self.kb.orders[p.order_id].base
                get = M.Task(self.kb.next_id("task"), M.GET_WORKPIECE,
                             {"machine": bs, "side": M.OUTPUT, "base": base, "role": EXTRA},
                             product=p.id, prepare={"machine": bs, "bs": {"side": M.OUTPUT,
                                                                          "color": base}},
                             locks=(bs,), releases=(bs,), created=self.kb.get("game_time", 0.0))
                self.kb.save_task(get)
                after.deps = tuple(get.id if d == pickup.id else d for d in after.deps)
                after.params = {**after.params, "carry_from": get.id}
                after.holder = None
                self.kb.save_task(after)
                p.tasks = tuple(p.tasks) + (get.id,)
                self.kb.save_product(p)
            self.buffers.take(cs, p.id)
            out.append(p)
            log.info("%s mounts the cap waiting in %s", p.id, cs)
        return out

    def cap_due(self, task: M.Task) -> bool:
        """Is it time for ``task``'s product to retrieve (or take) its cap?  Once every
        ring mount of the product that does not wait for the cap-less base is under
        way: a retrieved cap keeps its cap station from every other product until it
        is mounted."""
        product = self.kb.products.get(task.product or "")
        if product is None:
            return True
        tasks = self.kb.tasks_of(product.tasks)
        after, grew = {task.id}, True
        while grew:                              # the steps that wait for the cap
            grew = False
            for t in tasks:
                if t.id not in after and any(d in after for d in t.deps):
                    after.add(t.id)
                    grew = True
        return not any(t.kind == M.MOUNT_RING and t.state == M.PENDING and t.id not in after
                       for t in tasks)

    def cap_chain(self, product: M.Product, cs: str):
        """(retrieve, cap-less pickup, what takes the base) of ``product`` at ``cs``, all
        still PENDING; None if there is none."""
        tasks = self.kb.tasks_of(product.tasks)
        for r in tasks:
            if r.kind != M.RETRIEVE_CAP or r.machine != cs or r.state != M.PENDING:
                continue
            pick = [t for t in tasks if r.id in t.deps and t.kind == M.GET_WORKPIECE]
            if len(pick) != 1 or pick[0].state != M.PENDING:
                return None
            # what carries the cap-less base on (a ring mount waived off its put to a
            # full slide waits for the pickup too, but carries its own workpiece)
            after = [t for t in tasks if t.params.get("carry_from") == pick[0].id]
            if len(after) != 1 or after[0].state != M.PENDING:
                return None
            return r, pick[0], after[0]
        return None

    def prefill(self, game_time: float, horizon: float) -> list[M.Product]:
        """Retrieve a cap ahead into each idle cap station that holds none and that no
        product plans to use now, while an order may still want its colour: a later
        product mounts it at once (:meth:`adopt_free_caps`).  The cap-less base is
        discarded.  Returns the cleanup products made now."""
        if game_time > horizon - self.prefill_stop or not self.kb.orders:
            return []
        buf, made = self.buffers.owners, []
        later = self._not_due_yet()
        busy = {t.machine for t in self.kb.open_tasks() if t.machine and t.id not in later}
        prefilling = {t.machine for p in self.products.active() if p.order_id == CLEANUP_ORDER
                      for t in self.kb.tasks_of(p.tasks) if t.kind == M.RETRIEVE_CAP}
        for cs, cap in sorted(self.cs_caps.items()):
            st = self.kb.stations.get(cs)
            if buf.get(cs) is not None or cs in busy or cs in prefilling or st is None or \
                    st.state != "IDLE" or cs in self.world.unusable() or cs in self.locks.owners or \
                    self.shelves.dry(cs):
                continue
            wanted = any(o.cap == cap and o.open > 0 for o in self.kb.orders.values())
            if not wanted and game_time > self.prefill_unknown:
                continue
            product = self.products.new("X", CLEANUP_ORDER, created=game_time)
            ctx = ProductionContext(self.prefix, {}, {}, self.cs_caps, None)
            net = self.planner.htn.plan(ctx, Seq(("retrieve_cap", cs), ("pickup", cs, True,
                                                                          CAPLESS), ("discard",)))
            self.products.add_network(product, net)
            made.append(product)
            log.info("%s retrieves a cap into %s ahead", product.id, cs)
        return made

    def yield_prefills(self) -> list[M.Product]:
        """A cap retrieval ahead that has not started (its RETRIEVE_CAP pending: no robot
        took it yet, or it went back to the pool when its station went DOWN, keeping the
        station's lock) gives way to a product whose cap is due at that station: it is
        cancelled and its locks released.  Returns the retrievals given up."""
        due = set()
        for p in self.products.active():
            if p.order_id == CLEANUP_ORDER:
                continue
            for cs in self.cs_caps:
                chain = self.cap_chain(p, cs)
                if chain is not None and self.cap_due(chain[0]):
                    due.add(cs)
        out = []
        for p in self.products.active():
            if p.order_id != CLEANUP_ORDER:
                continue
            retrieve = [t for t in self.kb.tasks_of(p.tasks) if t.kind == M.RETRIEVE_CAP]
            if len(retrieve) != 1 or retrieve[0].state != M.PENDING or retrieve[0].machine not in due:
                continue
            self.products.cancel_open(p)             # all pending: no robot to stop
            p.state = ABANDONED
            self.kb.save_product(p)
            self.locks.release(p.id)
            out.append(p)
            log.info("%s gives up its cap ahead into %s: a product's cap is due there",
                     p.id, retrieve[0].machine)
        return out

    def _not_due_yet(self) -> set[int]:
        """Ids of the pending tasks at a cap station of products whose cap there is not
        due yet (:meth:`cap_due`): they use the station only later, and a cap retrieved
        ahead into it now is theirs to take once it is due (:meth:`adopt_free_caps`)."""
        out: set[int] = set()
        for p in self.products.active():
            for cs in self.cs_caps:
                chain = self.cap_chain(p, cs)
                if chain is not None and not self.cap_due(chain[0]):
                    out |= {t.id for t in self.kb.tasks_of(p.tasks)
                            if t.machine == cs and t.state == M.PENDING}
        return out

    def choose_shelf_slot(self, task: M.Task) -> None:
        """Set the shelf slot an assigned RETRIEVE_CAP takes its cap carrier from: one
        that holds a carrier and that the robots can reach (:mod:`.shelves`)."""
        task.params["shelf_slot"] = self.shelves.choose(task.machine, task.id)
        self.kb.save_task(task)

    def spare_robots(self) -> int:
        """Idle robots with empty grippers beyond the steps that could start now."""
        def idle(r: M.Robot) -> bool:
            t = self.kb.tasks.get(r.task_id) if r.task_id is not None else None
            return not r.holding and (t is None or t.kind == M.GO_TO)     # parking is idle
        idle = sum(1 for r in self.kb.active_robots() if idle(r))
        startable = sum(1 for t in self.kb.open_tasks() if t.state == M.PENDING and not t.carry
                        and all(self.kb.tasks.get(d) is not None
                                and self.kb.tasks[d].state == M.DONE for d in t.deps))
        return idle - startable
