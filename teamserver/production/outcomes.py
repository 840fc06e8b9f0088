"""What a finished task did: workpieces, buffers, locks and products booked.

When a task finishes, the workpieces it moved are updated (where each is,
which rings and cap it has), the cap stations' buffers and the storage
shelf follow, the station locks its product gives up are released, and
carry steps are bound to the robot that now holds the workpiece.
"""
from __future__ import annotations

from ..knowledge import model as M
from ..knowledge.kb import KnowledgeBase
from ..planning.domain import CAPLESS, EXTRA, MAIN
from .caps import FREE, CapBuffers
from .handover import Handover
from .locks import StationLocks
from .products import ACTIVE, CLEANUP_ORDER, DELIVERED
from .storage import Shelf


class Outcomes:
    """Books finished tasks (see the module doc).  ``ss``: our storage station."""

    def __init__(self, kb: KnowledgeBase, locks: StationLocks, buffers: CapBuffers,
                 shelf: Shelf, handover: Handover, *, ss: str | None):
        self.kb = kb
        self.locks = locks
        self.buffers = buffers
        self.shelf = shelf
        self.handover = handover
        self.ss = ss

    def task_done(self, task: M.Task, robot: M.Robot) -> None:
        """Book the effects of a finished task on workpieces, locks and buffers."""
        product = self.kb.products.get(task.product) if task.product else None
        kind, machine = task.kind, task.machine
        if kind == M.GET_WORKPIECE:
            role = task.params.get("role", MAIN)
            wp = self._workpiece_for_pickup(task, product, role)
            wp.location = f"robot:{robot.number}"
            self.kb.save_workpiece(wp)
            robot.holding = wp.id
            for other in self.kb.tasks_of(product.tasks if product else ()):
                if other.params.get("carry_from") == task.id and other.state == M.PENDING:
                    other.holder = robot.number
                    self.kb.save_task(other)
            if machine == self.ss and product is not None:
                self.shelf.free_place(product.id)       # retrieved
            elif product is not None and wp.cap is not None and role == MAIN:
                self.handover.redecide(product)         # finished: store it after all, or not
        elif kind == M.RETRIEVE_CAP:
            wp = M.Workpiece(f"{task.product}/capless{task.id}", base="?", cap=None,
                             location=f"{machine}:{M.OUTPUT}", product=task.product)
            self.kb.save_workpiece(wp)
            ahead = product is not None and product.order_id == CLEANUP_ORDER
            self.buffers.take(machine, FREE if ahead else task.product)
        elif kind in (M.MOUNT_RING, M.MOUNT_CAP):
            wp = self.kb.workpieces.get(robot.holding or "")
            if wp is not None:
                if kind == M.MOUNT_RING:
                    wp.rings = tuple(wp.rings) + (task.params["ring_color"],)
                else:
                    wp.cap = task.params.get("cap_color")
                    buf = self.buffers.owners
                    buf.pop(machine, None)
                    self.buffers.set(buf)
                wp.location = f"{machine}:{M.OUTPUT}"
                self.kb.save_workpiece(wp)
            robot.holding = None
        elif kind == M.PUT_WORKPIECE and task.params.get("store"):
            self.shelf.stored(task, self.kb.workpieces.get(
                (product.workpiece if product is not None else None) or robot.holding or ""))
            robot.holding = None
        elif kind in (M.PUT_WORKPIECE, M.DELIVER, M.DISCARD):
            wp = self.kb.workpieces.get(robot.holding or "")
            if wp is not None:
                wp.location = "gone"
                self.kb.save_workpiece(wp)
            robot.holding = None
            if kind == M.DELIVER and product is not None:
                product.state = DELIVERED
                product.delivered_at = float(self.kb.get("game_time", 0.0))
                self.kb.save_product(product)
                self.locks.release(product.id)
        if task.releases and product is not None:
            self.locks.release(product.id, set(task.releases))
        if (product is not None and product.state == ACTIVE and product.order_id == CLEANUP_ORDER
                and all(t.state in M.CLOSED_STATES for t in self.kb.tasks_of(product.tasks))):
            product.state = DELIVERED
            self.kb.save_product(product)
            self.locks.release(product.id)

    def _workpiece_for_pickup(self, task: M.Task, product: M.Product | None,
                              role: str) -> M.Workpiece:
        machine = task.machine
        here = f"{machine}:{M.OUTPUT}"
        if product is not None and role == MAIN:
            if machine.endswith("BS"):
                wp = M.Workpiece(f"{product.id}/wp{task.id}", base=task.params.get("base"),
                                 product=product.id)
            else:
                wp = self.kb.workpieces.get(product.workpiece or "") or M.Workpiece(
                    f"{product.id}/wp{task.id}", product=product.id)
            product.workpiece = wp.id
            self.kb.save_product(product)
            return wp
        if role == CAPLESS:
            for wp in self.kb.workpieces.values():
                if wp.location == here and wp.id.startswith(f"{task.product}/capless"):
                    return wp
        base = task.params.get("base") if machine.endswith("BS") else "?"
        return M.Workpiece(f"{task.product}/{EXTRA}{task.id}", base=base, product=task.product)
