"""Products and their tasks, as records in the knowledge base.

A :class:`~teamserver.knowledge.model.Product` owns the tasks of one unit of
an order (or, with order id :data:`CLEANUP_ORDER`, of a small job that only
clears a station or fills one).  :class:`Products` creates products, turns a
planned network into their tasks, copies a failed step for a retry, cancels
what is open of a product and marks a product for repair; the decisions
about *when* to do which are elsewhere (:mod:`.manager`, :mod:`.repair`).
"""
from __future__ import annotations

import logging

from ..knowledge import model as M
from ..knowledge.kb import KnowledgeBase
from ..planning.htn import Network
from .storage import Shelf

log = logging.getLogger("teamserver.production")

CLEANUP_ORDER = 0          # order id of products that only clear a station (or fill one)
DELIVERED, ABANDONED, ACTIVE = "DELIVERED", "ABANDONED", "ACTIVE"


class Products:
    """Product records and their tasks.  ``shelf``: the storage station's places,
    given to the STORE/RETRIEVE instructions of new tasks."""

    def __init__(self, kb: KnowledgeBase, shelf: Shelf):
        self.kb = kb
        self.shelf = shelf

    def active(self) -> list[M.Product]:
        return [p for p in self.kb.products.values() if p.state == ACTIVE]

    def new(self, letter: str, order_id: int, **fields) -> M.Product:
        """A new product (id ``letter`` + a counter: "P" for an order's, "X" for a
        clean-up), saved."""
        product = M.Product(f"{letter}{self.kb.next_id('product')}", order_id, **fields)
        self.kb.save_product(product)
        return product

    def add_network(self, product: M.Product, net: Network) -> list[M.Task]:
        """The steps of ``net`` as tasks of ``product`` (saved; returned)."""
        ids = [self.kb.next_id("task") for _ in net.steps]
        tasks = []
        for i, st in enumerate(net.steps):
            f = st.fields
            deps = tuple(ids[j] for j in net.predecessors(i))
            params = dict(f["params"])
            if f["carry"]:
                pick = [ids[j] for j in net.predecessors(i)
                        if net.steps[j].fields["kind"] == M.GET_WORKPIECE]
                if pick:
                    params["carry_from"] = pick[0]
            holder = int(f["holder"]) if f["holder"] is not None else None
            t = M.Task(ids[i], f["kind"], params, product=product.id, deps=deps,
                       prepare=f["prepare"], locks=f["locks"], releases=f["releases"],
                       carry=f["carry"], holder=holder, created=self.kb.get("game_time", 0.0))
            self.kb.save_task(t)
            tasks.append(t)
        product.tasks = tuple(product.tasks) + tuple(ids)
        self.kb.save_product(product)
        self.shelf.fill_places(product, tasks)
        return tasks

    def retry(self, task: M.Task) -> M.Task:
        """A fresh copy of a failed step under a new id (agents remember the outcome
        of a task id, so a retry must not reuse it); dependants follow the copy."""
        new = M.Task.from_dict({**task.to_dict(), "id": self.kb.next_id("task"),
                                "state": M.PENDING, "robot": None, "assigned_at": None,
                                "prepared_at": None, "finished_at": None})
        self.kb.save_task(new)
        task.state = M.FAILED
        self.kb.save_task(task)
        product = self.kb.products.get(task.product or "")
        if product is not None:
            product.tasks = tuple(product.tasks) + (new.id,)
            self.kb.save_product(product)
            for t in self.kb.tasks_of(product.tasks):
                changed = False
                if task.id in t.deps:
                    t.deps = tuple(new.id if d == task.id else d for d in t.deps)
                    changed = True
                if t.params.get("carry_from") == task.id:
                    t.params["carry_from"] = new.id
                    changed = True
                if changed:
                    self.kb.save_task(t)
        return new

    def needs_repair(self, product_id: str | None, why: str) -> None:
        """Mark a product to be planned again at the next planning round."""
        p = self.kb.products.get(product_id or "")
        if p is not None and p.state == ACTIVE and not p.repair:
            p.repair = why
            self.kb.save_product(p)
            log.info("%s needs repair: %s", p.id, why)

    def cancel_open(self, product: M.Product) -> list[M.Task]:
        """Cancel the product's open tasks; returns copies of those that were assigned
        (their robots must be told to stop), which no longer hold their robots."""
        cancels = []
        for t in self.kb.tasks_of(product.tasks):
            if t.state in M.OPEN_STATES:
                if t.state == M.ASSIGNED:
                    cancels.append(M.Task.from_dict(t.to_dict()))
                    r = self.kb.robots.get(t.robot)
                    if r is not None and r.task_id == t.id:
                        r.task_id = None
                        self.kb.save_robot(r)
                t.state = M.CANCELLED
                self.kb.save_task(t)
        return cancels
