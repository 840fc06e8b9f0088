"""Production: the objects that turn orders into products and keep their books,
wired together, and the planning round.

:class:`ProductionManager` builds the collaborators of production for our
team and hands each the others it needs:

- :attr:`~ProductionManager.products` (:mod:`.products`): product records
  and their tasks;
- :attr:`~ProductionManager.locks` (:mod:`.locks`): which product holds
  which station;
- :attr:`~ProductionManager.world` (:mod:`.world`): the planning world
  built from the knowledge base;
- :attr:`~ProductionManager.caps`, :attr:`~ProductionManager.buffers`
  (:mod:`.caps`): cap station buffers, caps retrieved ahead, when a cap is
  due; :attr:`~ProductionManager.cap_shelves` (:mod:`.shelves`): which
  shelf slot holds a cap carrier and can be reached;
- :attr:`~ProductionManager.slides` (:mod:`.slides`): bases on the ring
  stations' slides;
- :attr:`~ProductionManager.shelf`, :attr:`~ProductionManager.handover`
  (:mod:`.storage`, :mod:`.handover`): the storage station's places, and
  storing a finished product or not;
- :attr:`~ProductionManager.cleanup` (:mod:`.cleanup`): small products
  that clear a station or a gripper;
- :attr:`~ProductionManager.tracker`, :attr:`~ProductionManager.repairs`
  (:mod:`.tracker`, :mod:`.repair`): what exists of a product, and
  planning it again;
- :attr:`~ProductionManager.outcomes` (:mod:`.outcomes`): what a finished
  task did;
- :attr:`~ProductionManager.health` (:mod:`.health`): places the robots
  keep failing at.

:meth:`ProductionManager.plan` is one planning round: repair what needs
it, then start the orders the planner picks and, with robots to spare,
retrieve caps ahead.
"""
from __future__ import annotations

import logging

from ..knowledge import model as M
from ..knowledge.kb import KnowledgeBase
from ..planning.planner import Candidate, ProductionPlanner
from .caps import CapBuffers, Caps
from .cleanup import Cleanup
from .handover import Handover
from .health import StationHealth
from .locks import StationLocks
from .outcomes import Outcomes
from .products import Products
from .repair import Repairs
from .shelves import CapShelves
from .slides import Slides
from .storage import Shelf
from .tracker import Tracker
from .world import PlanningWorld

log = logging.getLogger("teamserver.production")


class ProductionManager:
    """Production for the team whose machines have ``prefix`` ("C"/"M").
    ``cs_caps``: cap colour on each cap station's shelf; ``max_products``:
    products at once (None: one per robot); ``max_repairs``: repairs of one
    product before it is abandoned; ``confirm_time``: game seconds a delivery
    may wait for the refbox to count it; ``prefill``: retrieve caps ahead."""

    def __init__(self, kb: KnowledgeBase, planner: ProductionPlanner, prefix: str, *,
                 cs_caps: dict[str, str], max_products: int | None = None,
                 max_repairs: int = 3, clock=None, confirm_time: float = 20.0,
                 prefill: bool = True):
        self.kb = kb
        self.planner = planner
        self.prefix = prefix
        self.cs_caps = {f"{prefix}-{k}" if not k.startswith(prefix + "-") else k: v
                        for k, v in cs_caps.items()}
        ss = planner.ss
        self.health = StationHealth(kb)
        self.locks = StationLocks(kb)
        self.shelf = Shelf(kb, ss)
        self.products = Products(kb, self.shelf)
        self.cap_shelves = CapShelves(kb)
        self.world = PlanningWorld(kb, planner, self.products, self.locks, self.shelf,
                                   self.health, prefix=prefix, cs_caps=self.cs_caps, clock=clock,
                                   max_products=max_products, confirm_time=confirm_time,
                                   cap_shelves=self.cap_shelves)
        self.buffers = CapBuffers(kb)
        self.caps = Caps(kb, self.buffers, self.products, planner, self.world, self.locks,
                         self.cap_shelves,
                         prefix=prefix, cs_caps=self.cs_caps, prefill=prefill)
        self.slides = Slides(kb, self.products, prefix=prefix, clock=clock, health=self.health)
        self.cleanup = Cleanup(kb, self.products, planner, self.shelf, prefix=prefix,
                               cs_caps=self.cs_caps)
        self.tracker = Tracker(kb, self.buffers, self.shelf)
        self.repairs = Repairs(kb, self.products, self.tracker, self.world, planner, self.locks,
                               self.buffers, self.shelf, self.cleanup, max_repairs=max_repairs)
        self.handover = Handover(kb, ss, self.shelf, self.products, self.repairs)
        self.outcomes = Outcomes(kb, self.locks, self.buffers, self.shelf, self.handover, ss=ss)

    def plan(self, game_time: float, horizon: float):
        """Repair what needs it, then start the orders the planner picks.
        Returns (tasks to cancel, the planner's Choice or None)."""
        cancels: list[M.Task] = []
        for p in self.products.active():
            if p.repair:
                cancels += self.repairs.repair(p)
            else:
                self.handover.redecide(p)
        if not self.world.ready_to_plan():
            return cancels, None
        self.caps.adopt_free_caps()
        choice = self.planner.choose(self.world.build(game_time, horizon))
        for cand in choice.start:
            self.start(cand)
        if self.caps.prefill_caps and self.caps.spare_robots() > 0:
            self.caps.prefill(game_time, horizon)
        return cancels, choice

    def start(self, cand: Candidate) -> M.Product:
        """A product for the chosen order, with the planned network's tasks."""
        product = self.products.new("P", cand.order.id, created=self.kb.get("game_time", 0.0))
        if cand.stock is not None:           # a C0 the storage station held from the start
            self.shelf.reserve(*cand.stock, product.id)
            o = cand.order
            wp = M.Workpiece(f"{product.id}/stock", base=o.base, cap=o.cap,
                             location=f"{self.shelf.ss}:{M.SHELF}", product=product.id)
            self.kb.save_workpiece(wp)
            product.workpiece = wp.id
            self.kb.save_product(product)
        self.products.add_network(product, cand.network)
        log.info("started %s for order %d (%d tasks)", product.id, cand.order.id,
                 len(cand.network.steps))
        return product
