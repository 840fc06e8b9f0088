"""Station locks: which product holds which station (or a cap station's cap).

A production task names the locks it needs (``Task.locks``: a station, or
``"C-CS1#cap"`` for the cap a cap station holds for a product) and the ones
it gives up when it is done (``Task.releases``).  A product takes its locks
when one of its tasks is assigned and keeps them across its steps, so that
no other product's workpiece gets between them.  The owners live in the
knowledge base (``locks``: lock name -> product id).
"""
from __future__ import annotations

from ..knowledge import model as M
from ..knowledge.kb import KnowledgeBase


class StationLocks:
    """Lock name -> owning product, kept in the knowledge base."""

    def __init__(self, kb: KnowledgeBase):
        self.kb = kb

    @property
    def owners(self) -> dict[str, str]:
        """Lock name -> product id (a copy)."""
        return dict(self.kb.get("locks", {}))

    def _set(self, locks: dict[str, str]) -> None:
        self.kb.set("locks", locks)

    def free_for(self, task: M.Task, but: str | None = None) -> bool:
        """Its product may take the task's locks, and no other running task uses them
        (a station serves one robot at a time, even within one product).  ``but``: a
        product whose locks count as given up."""
        if not task.locks:
            return True
        locks = self.owners
        if any(locks.get(lk, task.product) not in (task.product, but) for lk in task.locks):
            return False
        mine = set(task.locks)
        return not any(t.id != task.id and t.state == M.ASSIGNED and mine & set(t.locks)
                       for t in self.kb.open_tasks())

    def acquire(self, task: M.Task) -> None:
        """``task``'s product takes the task's locks."""
        if task.locks:
            locks = self.owners
            locks.update(dict.fromkeys(task.locks, task.product))
            self._set(locks)

    def grant(self, owned: dict[str, str]) -> None:
        """Give these locks (lock name -> product id) to their products."""
        locks = self.owners
        locks.update(owned)
        self._set(locks)

    def release(self, product: str, names=None) -> None:
        """``product`` gives up its locks (only ``names`` of them, if given)."""
        locks = self.owners
        for lk in list(locks):
            if locks[lk] == product and (names is None or lk in names):
                del locks[lk]
        self._set(locks)
