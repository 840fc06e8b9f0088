"""What exists of a product: its workpiece (where, with which rings and cap),
bases it has put on ring station slides, a cap a cap station holds for it,
and whether it is stored.  :meth:`Tracker.progress` is what a product is
planned again from (:class:`~teamserver.planning.domain.Progress`)."""
from __future__ import annotations

from ..knowledge import model as M
from ..knowledge.kb import KnowledgeBase
from ..planning.domain import Progress
from .caps import CapBuffers
from .storage import Shelf


class Tracker:
    """Reads a product's progress from the knowledge base, the cap buffers and the
    storage shelf."""

    def __init__(self, kb: KnowledgeBase, buffers: CapBuffers, shelf: Shelf):
        self.kb = kb
        self.buffers = buffers
        self.shelf = shelf

    def progress(self, product: M.Product) -> Progress:
        pr = Progress()
        wp = self.kb.workpieces.get(product.workpiece) if product.workpiece else None
        if wp is not None and self.workpiece_exists(wp):
            pr.base, pr.rings, pr.cap, pr.location = wp.base, tuple(wp.rings), wp.cap, wp.location
        credit: dict[str, int] = {}
        for t in self.kb.tasks_of(product.tasks):
            if t.state != M.DONE:
                continue
            if t.kind == M.PUT_WORKPIECE and t.params.get("side") == M.SLIDE:
                credit[t.machine] = credit.get(t.machine, 0) + 1
            elif t.kind == M.MOUNT_RING:
                credit[t.machine] = credit.get(t.machine, 0) - int(t.params.get("cost", 0))
        pr.slide_credit = {k: v for k, v in credit.items() if v > 0}
        for cs, owner in self.buffers.owners.items():
            if owner == product.id:
                pr.cap_ready = cs
        if pr.location is not None and pr.location.endswith(":" + M.SHELF):
            pr.stored_at = self.shelf.place_of(product.id)
            if self.shelf.brought_out(product):
                pr.location = f"{self.shelf.ss}:{M.OUTPUT}"
        return pr

    def workpiece_exists(self, wp: M.Workpiece) -> bool:
        loc = wp.location
        if loc == "gone":
            return False
        if loc.startswith("robot:"):
            r = self.kb.robots.get(int(loc[6:]))
            return r is not None and r.status == M.ACTIVE
        if loc.endswith(":" + M.SHELF):
            return True                 # a broken storage station keeps its shelf
        st = self.kb.stations.get(loc.split(":")[0])
        return st is None or st.state not in ("BROKEN",)
