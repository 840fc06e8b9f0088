"""Small products that only move a workpiece out of the way (order id 0):
take one from a station output and discard it, discard what a robot holds,
or feed a spare base to a station left PREPARED for nothing."""
from __future__ import annotations

from ..knowledge import model as M
from ..knowledge.kb import KnowledgeBase
from ..planning.domain import CAPLESS, EXTRA
from ..planning.htn import Seq
from ..planning.planner import ProductionPlanner
from .products import CLEANUP_ORDER, Products
from .storage import Shelf


class Cleanup:
    """Makes clean-up products (see the module doc) for our team (``prefix``)."""

    def __init__(self, kb: KnowledgeBase, products: Products, planner: ProductionPlanner,
                 shelf: Shelf, *, prefix: str, cs_caps: dict[str, str]):
        self.kb = kb
        self.products = products
        self.planner = planner
        self.shelf = shelf
        self.prefix = prefix
        self.cs_caps = cs_caps

    def clear_output(self, machine: str) -> M.Product:
        """A small product that takes a workpiece from ``machine``'s output and discards it."""
        product = self.products.new("X", CLEANUP_ORDER)
        ctx = None
        net = self.planner.htn.plan(ctx, Seq(("pickup", machine, False, CAPLESS),
                                             ("discard",)))
        self.products.add_network(product, net)
        return product

    def flush(self, machine: str, instruction: dict) -> M.Product | None:
        """A small product that feeds a spare base to ``machine``, PREPARED with
        ``instruction`` that nothing needs, so that it processes it and becomes IDLE
        again (a ring or cap station's result is taken away and discarded; a storage
        station keeps the base at the STORE's place, reserved for good)."""
        kind = machine[2:4]
        bs = f"{self.prefix}-BS"
        base = "BASE_RED"
        if kind == "DS":
            feed = (M.DELIVER, {"machine": machine, **instruction.get("ds", {})})
        elif kind == "RS" and "rs" in instruction:
            feed = (M.MOUNT_RING, {"machine": machine, "cost": 0, **instruction["rs"]})
        elif kind == "CS":
            feed = (M.MOUNT_CAP, {"machine": machine, "cap_color": self.cs_caps.get(machine)})
        elif kind == "SS" and instruction.get("ss", {}).get("operation") == "STORE":
            feed = (M.PUT_WORKPIECE, {"machine": machine, "side": M.INPUT, "store": True})
        else:
            return None
        only_feed = kind in ("DS", "SS")        # nothing comes out to take away
        product = self.products.new("X", CLEANUP_ORDER, created=self.kb.get("game_time", 0.0))
        pid = product.id
        now = self.kb.get("game_time", 0.0)
        ids = [self.kb.next_id("task") for _ in range(2 if only_feed else 4)]
        tasks = [M.Task(ids[0], M.GET_WORKPIECE, {"machine": bs, "side": M.OUTPUT, "base": base,
                                                  "role": EXTRA},
                        product=pid, prepare={"machine": bs, "bs": {"side": M.OUTPUT,
                                                                    "color": base}},
                        locks=(bs,), releases=(bs,), created=now),
                 M.Task(ids[1], feed[0], {**feed[1], "carry_from": ids[0]}, product=pid,
                        deps=(ids[0],), locks=(machine,),
                        releases=(machine,) if only_feed else (), carry=True, created=now)]
        if kind == "SS":
            ss = instruction["ss"]
            self.shelf.reserve(ss["shelf"], ss["slot"], pid)
        if not only_feed:
            tasks += [M.Task(ids[2], M.GET_WORKPIECE, {"machine": machine, "side": M.OUTPUT,
                                                       "role": EXTRA},
                             product=pid, deps=(ids[1],), locks=(machine,),
                             releases=(machine,), created=now),
                      M.Task(ids[3], M.DISCARD, {"carry_from": ids[2]}, product=pid,
                             deps=(ids[2],), carry=True, created=now)]
        for t in tasks:
            self.kb.save_task(t)
        product.tasks = tuple(ids)
        self.kb.save_product(product)
        return product

    def discard_for(self, robot: M.Robot) -> M.Task:
        """A task for a robot holding a workpiece nothing needs: discard it."""
        product = self.products.new("X", CLEANUP_ORDER)
        t = M.Task(self.kb.next_id("task"), M.DISCARD, {}, product=product.id, carry=True,
                   holder=robot.number, created=self.kb.get("game_time", 0.0))
        self.kb.save_task(t)
        product.tasks = (t.id,)
        self.kb.save_product(product)
        return t
