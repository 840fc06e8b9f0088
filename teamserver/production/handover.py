"""Store a finished product or hand it over directly: the choice made again.

The planner decides whether a product waits in the storage station when it
plans the product (:class:`~teamserver.planning.planner.StoragePolicy`).
Once the product is finished the clock has moved on, so :class:`Handover`
makes the choice again from now (:meth:`Handover.redecide`): at the pickup
from the cap station and at every planning round while no robot is on its
way with it.
"""
from __future__ import annotations

import logging

from ..knowledge import model as M
from ..knowledge.kb import KnowledgeBase
from ..planning.htn import PlanningFailed
from .products import Products
from .repair import Repairs
from .storage import Shelf, stores

log = logging.getLogger("teamserver.production")


class Handover:
    """See the module doc.  ``ss``: our storage station (None: no storing)."""

    def __init__(self, kb: KnowledgeBase, ss: str | None, shelf: Shelf, products: Products,
                 repairs: Repairs):
        self.kb = kb
        self.ss = ss
        self.shelf = shelf
        self.products = products
        self.repairs = repairs

    def redecide(self, product: M.Product) -> bool:
        """Plan the hand-over of a finished ``product`` again from now, if no robot is on
        its way with it yet: store it when that pays now, else hand it over directly.
        True if the plan changed."""
        if self.ss is None or product.state != "ACTIVE" or product.repair:
            return False
        wp = self.kb.workpieces.get(product.workpiece or "")
        if wp is None or wp.cap is None or wp.location == "gone" or self.shelf.is_stored(product):
            return False
        if any(t.machine == self.ss and t.state == M.DONE for t in self.kb.tasks_of(product.tasks)):
            return False                # it went through the storage station once already
        open_tasks = [t for t in self.kb.tasks_of(product.tasks) if t.state in M.OPEN_STATES]
        if not open_tasks or any(t.state == M.ASSIGNED for t in open_tasks):
            return False
        order = self.kb.orders.get(product.order_id)
        if order is None or order.open <= 0:
            return False
        try:
            net = self.repairs.plan_rest(product, order)
        except PlanningFailed:
            return False
        if stores(s.fields for s in net.steps) == stores(open_tasks):
            return False
        self.repairs.restart(product)
        self.products.add_network(product, net)
        log.info("%s is %s", product.id, "stored until its window" if stores(
            s.fields for s in net.steps) else "handed over directly after all")
        return True
