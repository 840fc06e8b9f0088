"""Robots and stations that drop out under an assigned task.

- A robot silent for ``heartbeat_timeout`` seconds and past every task
  lease the server granted it (:mod:`teamserver.links.leases`) is dropped
  (:meth:`Dropouts.check_heartbeats`): its task goes back to the pool, or,
  if it carried a workpiece, the product is repaired; so is every product
  whose next step waited for what it held.
- A task whose station goes BROKEN or DOWN before its PrepareMachine went
  out, its robot carrying nothing for it, goes back to the pool and the
  robot is free again (:meth:`Dropouts.release_unusable`); it goes to
  another robot only once this one has provably stopped it (the cancel may
  be lost in a cut: :meth:`~teamserver.dispatch.readiness.Readiness.held_by`).
"""
from __future__ import annotations

import logging

from ..knowledge import model as M
from ..knowledge.kb import KnowledgeBase
from ..links.tasks import TaskLink
from ..production.products import Products
from .config import DispatchConfig
from .fleet import PICKUPS, Fleet
from .readiness import Readiness

log = logging.getLogger("teamserver.dispatch")


class Dropouts:
    """See the module doc."""

    def __init__(self, kb: KnowledgeBase, clock, fleet: Fleet, readiness: Readiness,
                 products: Products, tasks: TaskLink, config: DispatchConfig):
        self.kb = kb
        self.clock = clock
        self.fleet = fleet
        self.readiness = readiness
        self.products = products
        self.tasks = tasks
        self.config = config

    def check_heartbeats(self) -> list[M.Robot]:
        """Drop robots silent for too long; returns the ones dropped now."""
        now = self.clock.now()
        dropped = []
        for r in list(self.kb.robots.values()):
            if r.status == M.ACTIVE and self.tasks.past_lease(r, self.config.heartbeat_timeout, now):
                self.drop(r, f"no heartbeat for {now - r.last_heartbeat:.1f} s")
                dropped.append(r)
        return dropped

    def drop(self, robot: M.Robot, why: str) -> None:
        log.warning("robot %d dropped: %s", robot.number, why)
        robot.status = M.LOST
        self.tasks.stopped(robot.number)        # past its lease: it stopped what was cancelled on it
        task = self.kb.tasks.get(robot.task_id) if robot.task_id is not None else None
        robot.task_id = None
        if robot.holding:
            wp = self.kb.workpieces.get(robot.holding)
            if wp is not None:
                wp.location = "gone"
                self.kb.save_workpiece(wp)
                self.products.needs_repair(wp.product, f"robot {robot.number} lost with it")
            robot.holding = None
        self.kb.save_robot(robot)
        if task is not None and task.state == M.ASSIGNED and task.kind == M.GO_TO:
            task.state = M.CANCELLED
            self.kb.save_task(task)
        elif task is not None and task.state == M.ASSIGNED:
            if task.carry:
                task.state = M.CANCELLED
                task.error = f"robot {robot.number} lost"
                self.kb.save_task(task)
                self.products.needs_repair(task.product, f"robot {robot.number} lost")
            else:
                self.fleet.back_to_pool(task, f"robot {robot.number} lost")
        # carry tasks bound to this robot can no longer be done by it
        for t in self.kb.open_tasks():
            if t.holder == robot.number and t.state == M.PENDING:
                self.products.needs_repair(t.product, f"robot {robot.number} lost")

    def release_unusable(self) -> list[M.Task]:
        """Assigned tasks whose station went BROKEN or DOWN before their
        PrepareMachine went out, and whose robot carries nothing for it, go back
        to the pool: the robot is told to stop and is free for other work
        instead of waiting at the station, once it said what it holds if it was
        picking something up (:meth:`Fleet.hold_back`: it may have grabbed the
        workpiece just before).  Returns the tasks released."""
        out = []
        for t in self.kb.open_tasks():
            if (t.state != M.ASSIGNED or t.carry or t.prepared_at is not None
                    or t.kind in (M.GO_TO, M.EXPLORE_ZONE)
                    or self.readiness.station_usable(t.machine)):
                continue
            robot = self.kb.robots.get(t.robot) if t.robot is not None else None
            state = self.kb.stations[t.machine].state
            self.tasks.cancel(t, f"{t.machine} is {state}")
            self.fleet.back_to_pool(t, f"{t.machine} {state} before it was prepared")
            if robot is not None and robot.task_id == t.id:
                robot.task_id = None
                self.kb.save_robot(robot)
                if t.kind in PICKUPS:
                    self.fleet.hold_back(robot, t)
            log.info("task %d released: %s is %s", t.id, t.machine, state)
            out.append(t)
        return out
