"""Task results from the robots: done, failed, cancelled.

A task's result (the robot's echoed AgentTask) closes it.  A success books what the task did
(:mod:`teamserver.production.outcomes`) and starts checking that its
station took the workpiece (:mod:`teamserver.production.feeding`); a feed
reported failed although its station took the workpiece counts as done.
A failure after which the same step may simply be tried again
(:data:`RETRY_ERRORS`, at most ``max_attempts`` times, not at a place the
robots keep failing at, not a cap retrieval from a shelf gone dry:
:mod:`teamserver.production.shelves`) gets a fresh copy of the step; any other failure,
or a lost workpiece, has the product repaired.  Every outcome at a station
is counted by :mod:`teamserver.production.health`.  A task queued behind the
one whose result came starts, or goes back to the pool (:meth:`Fleet.after_result`).
"""
from __future__ import annotations

import logging

from ..knowledge import model as M
from ..knowledge.kb import KnowledgeBase
from ..links.tasks import TaskLink
from ..production.feeding import FeedMonitor
from ..production.health import StationHealth
from ..production.outcomes import Outcomes
from ..production.products import Products
from ..production.repair import Repairs
from ..production.shelves import CapShelves
from .config import DispatchConfig
from .discards import Discards
from .fleet import Fleet
from .parking import Parking

log = logging.getLogger("teamserver.dispatch")

#: errors after which the same step is simply tried again
RETRY_ERRORS = {"NAVIGATION_FAILED", "LOCALISATION_LOST", "MACHINE_NOT_FOUND", "ALIGN_FAILED",
                "SENSOR_LOST", "GRAB_FAILED", "TIMEOUT", "NOT_RUNNING", "MACHINE_BROKEN", "NONE"}


class Results:
    """See the module doc."""

    def __init__(self, kb: KnowledgeBase, clock, *, feeds: FeedMonitor, outcomes: Outcomes,
                 products: Products, repairs: Repairs, health: StationHealth,
                 shelves: CapShelves, parking: Parking, discards: Discards, tasks: TaskLink, config: DispatchConfig,
                 fleet: Fleet):
        self.kb = kb
        self.clock = clock
        self.feeds = feeds
        self.outcomes = outcomes
        self.products = products
        self.repairs = repairs
        self.health = health
        self.shelves = shelves
        self.parking = parking
        self.discards = discards
        self.tasks = tasks
        self.config = config
        self.fleet = fleet

    def on_result(self, robot_number: int, task_id: int, status: str, error: str = "NONE",
                  holding: bool | None = None, text: str = "") -> None:
        """A task's result: ``status`` RUNNING/SUCCEEDED/FAILED/CANCELLED, ``error`` the
        ErrorCode name, ``holding`` whether the gripper holds something afterwards
        (None: not said)."""
        task = self.kb.tasks.get(task_id)
        robot = self.kb.robots.get(robot_number)
        if task is None or robot is None:
            return
        current = status != "RUNNING" and robot.task_id == task.id and task.robot == robot_number \
            and task.state == M.ASSIGNED
        self._booked(task, robot, status, error, holding, text)
        if current:
            self.fleet.after_result(robot, task)       # the task queued behind it starts, or goes back

    def _booked(self, task: M.Task, robot: M.Robot, status: str, error: str, holding: bool | None,
                text: str) -> None:
        robot_number = robot.number
        if task.robot != robot_number or task.state != M.ASSIGNED:
            if status == "RUNNING" and task.robot != robot_number:
                self.tasks.cancel(task, "task no longer yours")
            elif status != "RUNNING":
                self._taken_back(task, robot, holding)
            return
        if status == "RUNNING":
            return
        if task.after is not None and robot.task_id != task.id and error == "NOT_RUNNING":
            self.fleet.back_to_pool(task, text or "refused behind its robot's task")   # it never began
            return
        task.after = None
        if robot.task_id == task.id:
            robot.task_id = None
        task.finished_at = self.clock.now()
        if task.kind == M.GO_TO:
            task.state = M.DONE if status == "SUCCEEDED" else M.FAILED
            task.error = None if status == "SUCCEEDED" else (f"{error}: {text}" if text else error)
            self.kb.save_task(task)
            self.kb.save_robot(robot)
            if status != "SUCCEEDED":
                self.parking.failed(robot)
            return
        if status == "FAILED" and self.feeds.took(task):
            log.info("task %d failed (%s), but %s took its workpiece: done", task.id, error,
                     task.machine)
            status = "SUCCEEDED"
        if task.kind == M.DISCARD and status != "CANCELLED":
            self.discards.outcome(robot, status == "SUCCEEDED")
        if status != "CANCELLED":
            self.health.outcome(task, status == "SUCCEEDED", error, self.clock.now())
            self.shelves.outcome(task, status == "SUCCEEDED", error, text, holding)
        if status == "SUCCEEDED":
            task.state = M.DONE
            self.kb.save_task(task)
            if task.kind == M.EXPLORE_ZONE:
                self.kb.mark_visited(int(task.params["zone"]), self.clock.now())
            else:
                self.outcomes.task_done(task, robot)
                self.feeds.finished(task)
            self.kb.save_robot(robot)
            return
        task.error = f"{error}: {text}" if text else error
        if status == "CANCELLED" or task.kind == M.EXPLORE_ZONE:
            task.state = M.CANCELLED if status == "CANCELLED" else M.FAILED
            self.kb.save_task(task)
            if task.kind != M.EXPLORE_ZONE:
                self.products.needs_repair(task.product, f"task {task.id} cancelled")
            self.kb.save_robot(robot)
            return
        self._failed(task, robot, error, holding)

    def _taken_back(self, task: M.Task, robot: M.Robot, holding: bool | None) -> None:
        """The final result of a task taken back from ``robot`` (cancelled, back in the
        pool): if it says the gripper holds something the server booked nowhere, the
        robot holds an unknown workpiece (it gets no work needing an empty gripper,
        and is told to discard it)."""
        self.discards.fleet.heard(robot.number, task.id)
        now = self.kb.tasks.get(robot.task_id) if robot.task_id is not None else None
        if holding and robot.holding is None and (now is None or now.kind == M.GO_TO):
            if self._grabbed(task, robot):
                return
            robot.holding = "?"
            self.kb.save_robot(robot)
            log.warning("robot %d holds a workpiece after task %d was taken back: unknown, "
                        "to be discarded", robot.number, task.id)

    def _grabbed(self, task: M.Task, robot: M.Robot) -> bool:
        """A pickup from a station's output taken back and still in the pool (its station
        went DOWN or BROKEN before it was prepared, which a pickup from an output never
        is), whose robot says it holds a workpiece: it took that workpiece before it
        stopped (it was given the pickup with an empty gripper).  The pickup is booked
        done and the product goes on from the gripper, instead of the workpiece being
        discarded as unknown and the pickup sent again to an empty output (rcll2016
        seed 12 at 3b1cd15: C-CS1 went DOWN 1.4 s after the grab; GRAB_FAILED twice, the
        product abandoned).  Returns whether it did so."""
        if task.kind != M.GET_WORKPIECE or task.state != M.PENDING or task.robot is not None:
            return False
        task.state, task.robot, task.error = M.DONE, robot.number, None
        task.finished_at = self.clock.now()
        self.kb.save_task(task)
        self.outcomes.task_done(task, robot)
        self.kb.save_robot(robot)
        log.info("robot %d took the workpiece of task %d before it was taken back: done",
                 robot.number, task.id)
        return True

    def _failed(self, task: M.Task, robot: M.Robot, error: str, holding: bool | None) -> None:
        lost = False
        if task.carry and holding is False:
            lost = True                      # the workpiece it carried is gone
        if not task.carry and task.kind == M.GET_WORKPIECE and holding:
            lost = False
        if lost and robot.holding:
            wp = self.kb.workpieces.get(robot.holding)
            if wp is not None:
                wp.location = "gone"
                self.kb.save_workpiece(wp)
            robot.holding = None
        if holding and not task.carry and task.kind != M.GET_WORKPIECE and robot.holding is None:
            # it grabbed before it failed (a RetrieveCap's cap carrier, its cap
            # station gone DOWN): unknown to the books, to be discarded, never fed
            robot.holding = "?"
            log.warning("robot %d holds a workpiece after its %s %d failed: unknown, to be discarded",
                        robot.number, task.kind, task.id)
        self.kb.save_robot(robot)
        if error == "MACHINE_BROKEN" and task.machine:
            st = self.kb.stations.get(task.machine)
            if st is not None and st.state == "BROKEN":
                self.repairs.station_broke(task.machine)
        retry = (not lost and error in RETRY_ERRORS and task.attempts < self.config.max_attempts
                 and not (task.kind == M.DISCARD and not task.machine)
                 and not (task.kind == M.RETRIEVE_CAP and self.shelves.dry(task.machine or ""))
                 and self.health.usable(task, self.clock.now()))
        if retry:
            again = self.products.retry(task)
            log.info("task %d failed (%s), trying again as %d", task.id, error, again.id)
            if again.carry:
                again.holder = robot.number
                self.kb.save_task(again)
            return
        task.state = M.FAILED
        self.kb.save_task(task)
        self.products.needs_repair(task.product, f"task {task.id} {task.kind} failed: {error}")
