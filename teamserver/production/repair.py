"""Repair: a product that cannot go on as planned is planned again from what exists.

A failed step, a station that broke with the workpiece inside, a robot lost
with it, a feed the station never took: the product is marked
(:meth:`~teamserver.production.products.Products.needs_repair`) and at the
next planning round :meth:`Repairs.repair` cancels its open tasks and plans
the rest from what exists of it (the workpiece as it is, bases already on a
slide, a cap already buffered: :mod:`.tracker`); if nothing can be made of
it, it is abandoned and a station output it blocks is cleared.
"""
from __future__ import annotations

import logging

from ..knowledge import model as M
from ..knowledge.kb import KnowledgeBase
from ..planning.domain import CAP_LOCK, Progress
from ..planning.htn import Network, PlanningFailed
from ..planning.planner import ProductionPlanner
from .caps import FREE, CapBuffers
from .cleanup import Cleanup
from .locks import StationLocks
from .products import ABANDONED, ACTIVE, DELIVERED, Products
from .storage import Shelf
from .tracker import Tracker
from .world import PlanningWorld

log = logging.getLogger("teamserver.production")


class Repairs:
    """See the module doc.  ``max_repairs``: repairs of one product before it is
    abandoned."""

    def __init__(self, kb: KnowledgeBase, products: Products, tracker: Tracker,
                 world: PlanningWorld, planner: ProductionPlanner, locks: StationLocks,
                 buffers: CapBuffers, shelf: Shelf, cleanup: Cleanup, *, max_repairs: int = 3):
        self.kb = kb
        self.products = products
        self.tracker = tracker
        self.world = world
        self.planner = planner
        self.locks = locks
        self.buffers = buffers
        self.shelf = shelf
        self.cleanup = cleanup
        self.max_repairs = max_repairs

    def plan_rest(self, product: M.Product, order: M.Order) -> Network:
        """The rest of ``product`` from what exists (raises PlanningFailed)."""
        world = self.world.build(float(self.kb.get("game_time", 0.0)), 0.0, exclude=product.id)
        return self.planner.decompose(
            self.planner.context(world, order, self.tracker.progress(product)), world)

    def repair(self, product: M.Product) -> list[M.Task]:
        """Cancel the product's open tasks and plan the rest again; returns the
        tasks that were assigned (the robots must be told to stop)."""
        cancels = self.restart(product)
        product.repair, product.repairs = None, product.repairs + 1
        order = self.kb.orders.get(product.order_id)
        net = None
        if order is not None and order.open > 0 and product.repairs <= self.max_repairs:
            try:
                net = self.plan_rest(product, order)
            except PlanningFailed as exc:
                log.info("%s cannot be repaired: %s", product.id, exc)
        if net is None:
            self.abandon(product)
        else:
            self.products.add_network(product, net)
            self.kb.save_product(product)
        return cancels

    def restart(self, product: M.Product) -> list[M.Task]:
        """Cancel the product's open tasks and keep only the locks of what exists of it
        (a buffered cap, the station output its workpiece is on); returns the tasks
        that were assigned."""
        cancels = self.products.cancel_open(product)
        pr = self.tracker.progress(product)
        self.locks.release(product.id)
        owned = {}
        if pr.cap_ready:
            owned[pr.cap_ready + CAP_LOCK] = product.id
        if pr.location and pr.location.endswith(":" + M.OUTPUT):
            owned[pr.location.split(":")[0]] = product.id
        if owned:
            self.locks.grant(owned)
        return cancels

    def abandon(self, product: M.Product, pr: Progress | None = None) -> None:
        pr = pr or self.tracker.progress(product)
        product.state = ABANDONED
        self.kb.save_product(product)
        self.locks.release(product.id)
        buf = self.buffers.owners
        for cs in [cs for cs, owner in buf.items() if owner == product.id]:
            buf[cs] = FREE              # a retrieved cap another product can mount
        self.buffers.set(buf)
        if pr.location and pr.location.endswith(":" + M.SHELF):
            pass                        # it stays on the shelf; so does its reservation
        elif pr.location and not pr.location.startswith("robot:"):
            self.cleanup.clear_output(pr.location.split(":")[0])
            self.shelf.free_place(product.id)
        else:
            self.shelf.free_place(product.id)
        log.info("abandoned %s", product.id)

    def station_broke(self, machine: str) -> None:
        """A BROKEN station loses what it holds: workpieces inside, a buffered cap (but
        not the storage station's shelf)."""
        for wp in self.kb.workpieces.values():
            if wp.location.startswith(machine + ":") and not wp.location.endswith(M.SHELF):
                wp.location = "gone"
                self.kb.save_workpiece(wp)
                self.products.needs_repair(wp.product, f"{machine} broke with its workpiece")
        buf = self.buffers.owners
        owner = buf.pop(machine, None)
        if owner is not None:
            self.buffers.set(buf)
            self.products.needs_repair(owner, f"{machine} broke and lost the buffered cap")
        for t in self.kb.open_tasks():
            if t.machine == machine and t.prepared_at is not None and t.state == M.ASSIGNED:
                t.prepared_at = None            # to be prepared again once it is IDLE
                self.kb.save_task(t)

    def feed_lost(self, task: M.Task) -> None:
        """``task`` was reported done, but its station never took the workpiece: undo
        what :meth:`~teamserver.production.outcomes.Outcomes.task_done` booked and
        repair the product."""
        task.state, task.error = M.FAILED, "the station never took the workpiece"
        self.kb.save_task(task)
        machine = task.machine
        for wp in self.kb.workpieces.values():
            if wp.product == task.product and wp.location.startswith(machine + ":"):
                wp.location = "gone"
                self.kb.save_workpiece(wp)
        product = self.kb.products.get(task.product or "")
        buf = self.buffers.owners
        if task.kind == M.MOUNT_CAP and product is not None:
            buf[machine] = product.id               # the cap is still in the station
        elif task.kind == M.RETRIEVE_CAP:
            # the carrier never got there: the cap task_done booked in the
            # station is not there either, whoever has claimed it since
            owner = buf.pop(machine, None)
            if owner not in (None, FREE, task.product):
                self.products.needs_repair(owner, f"{machine} never got the cap it was to mount")
        self.buffers.set(buf)
        if product is None:
            return
        if product.state == DELIVERED:
            product.state, product.delivered_at = ACTIVE, None
            self.kb.save_product(product)
        # a clean-up product has no order: its repair cancels what is left of it and
        # frees its locks (its tasks would wait for a station output that never comes)
        self.products.needs_repair(product.id,
                                   f"{machine} never took the workpiece of task {task.id}")
