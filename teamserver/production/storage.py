"""The storage station's shelf (rcll2025): where finished products wait for their window.

An order's product delivered before its window opens scores nothing, so a
product finished early must wait.  Without a storage station a robot holds
it (and can do nothing else) or it stays on the cap station's output (and
blocks that station).  The planner stores such a product in the SS instead
when the wait is long enough to pay for the detour (see
:mod:`teamserver.planning.planner` and ``docs/planning.md``; whether to
store is decided again later by :mod:`.handover`).  :class:`Shelf` keeps the
books:

- each storing product gets one shelf place (shelf 0-5, slot 0-7) for its
  STORE and RETRIEVE instructions (:meth:`Shelf.fill_places`): its own
  again after a failed store, else the first place neither reserved by
  another product nor reported filled by the refbox (MachineInfo
  ``status_ss``);
- the place is reserved until the product is retrieved; a place holding a
  workpiece nobody will fetch (an abandoned product, a spare base that
  flushed a stale STORE) stays reserved for good.

A stored product still counts against ``max_products``: its robot helps
the products under way instead of one more starting (with three robots
on four products, fewer were finished).  The places live in the knowledge
base (``ss_places``: ``"shelf,slot"`` -> product id).
"""
from __future__ import annotations

import logging

from ..knowledge import model as M
from ..knowledge.kb import KnowledgeBase

log = logging.getLogger("teamserver.production")

SHELVES, SLOTS = 6, 8          # the refbox's SS-MAX-SHELF + 1, SS-MAX-SLOT + 1


def place_key(shelf: int, slot: int) -> str:
    return f"{int(shelf)},{int(slot)}"


def stores(steps) -> bool:
    """Does a plan (tasks or network steps' fields) put its product into storage?"""
    return any(s["params"].get("store") if isinstance(s, dict) else s.params.get("store")
               for s in steps)


class Shelf:
    """The places of storage station ``ss`` (None: the rules have none)."""

    def __init__(self, kb: KnowledgeBase, ss: str | None):
        self.kb = kb
        self.ss = ss

    # -- places ---------------------------------------------------------------------
    @property
    def places(self) -> dict[str, str]:
        """``"shelf,slot"`` -> the product it is reserved for (a copy)."""
        return dict(self.kb.get("ss_places", {}))

    def _set(self, places: dict[str, str]) -> None:
        self.kb.set("ss_places", places)

    def reserve(self, shelf: int, slot: int, product_id: str) -> None:
        """Reserve a place for ``product_id`` (for good, unless it is freed)."""
        self._set({**self.places, place_key(shelf, slot): product_id})

    def storage_place(self, product_id: str) -> tuple[int, int] | None:
        """The shelf place for ``product_id`` (reserved now), None when all are taken."""
        mine = self.place_of(product_id)
        if mine is not None:
            return mine
        places = self.places
        ss = self.kb.stations.get(self.ss or "")
        filled = set(ss.shelf if ss is not None else ())
        for shelf in range(SHELVES):
            for slot in range(SLOTS):
                key = place_key(shelf, slot)
                if key not in places and key not in filled:
                    places[key] = product_id
                    self._set(places)
                    return shelf, slot
        return None

    def storage_open(self) -> bool:
        """May a product be stored now: the storage station is neither BROKEN nor DOWN and
        has a free place?"""
        ss = self.kb.stations.get(self.ss or "")
        if ss is not None and ss.state in ("BROKEN", "DOWN"):
            return False
        taken = set(self.places) | set(ss.shelf if ss is not None else ())
        return len(taken) < SHELVES * SLOTS

    def place_of(self, product_id: str) -> tuple[int, int] | None:
        """The place reserved for ``product_id`` (where its workpiece is stored, if it is)."""
        for key, owner in sorted(self.places.items()):
            if owner == product_id:
                return tuple(int(v) for v in key.split(","))
        return None

    def free_place(self, product_id: str) -> None:
        """``product_id`` no longer needs its place (retrieved, or never stored)."""
        places = {k: v for k, v in self.places.items() if v != product_id}
        self._set(places)

    def fill_places(self, product: M.Product, tasks: list[M.Task]) -> None:
        """Give the STORE/RETRIEVE instructions of ``tasks`` ``product``'s shelf place."""
        need = [t for t in tasks if t.prepare and "ss" in t.prepare
                and t.prepare["ss"].get("shelf") is None]
        if not need:
            return
        place = self.storage_place(product.id)
        if place is None:
            log.warning("the storage station is full: %s has no place", product.id)
            return
        for t in need:
            t.prepare = {**t.prepare, "ss": {**t.prepare["ss"], "shelf": place[0],
                                             "slot": place[1]}}
            self.kb.save_task(t)

    # -- books ------------------------------------------------------------------------
    def stored(self, task: M.Task, wp: M.Workpiece | None) -> None:
        """A STORE put finished: the workpiece is on the shelf."""
        if wp is not None:
            wp.location = f"{task.machine}:{M.SHELF}"
            self.kb.save_workpiece(wp)
            log.info("%s stored in %s at %s", wp.product, task.machine,
                     (task.prepare or {}).get("ss"))

    def is_stored(self, product: M.Product) -> bool:
        wp = self.kb.workpieces.get(product.workpiece or "")
        return wp is not None and wp.location.endswith(":" + M.SHELF)

    def brought_out(self, product: M.Product) -> bool:
        """Has the storage station brought ``product``'s stored workpiece to its output
        (its RETRIEVE went out and the station is busy with it or waits for the pickup)?
        A pickup that failed there leaves it on the output, no longer on the shelf."""
        ss = self.kb.stations.get(self.ss or "")
        if ss is None or ss.state not in ("PROCESSING", "READY-AT-OUTPUT"):
            return False
        return any(t.prepare and t.prepare.get("ss", {}).get("operation") == "RETRIEVE"
                   and t.prepared_at is not None and t.prepared_at <= ss.since
                   for t in self.kb.tasks_of(product.tasks))
