"""The robots as the dispatcher sees them: who is idle, who may get work, and
giving a robot a task.

A robot is *idle* without a task; a robot driving to a parking spot (a
GO_TO task) is *available* too: real work cancels its GO_TO.  Assigning a
task takes its station locks, tells the robot through the task link and
cancels the robot's parking.

A robot whose pickup the server took back (:meth:`Fleet.hold_back`: its
station went BROKEN or DOWN, or its product was planned again,
:meth:`Fleet.took_back`) may have grabbed the workpiece just before: it gets no
new work until its result of that task says what its gripper holds
(:meth:`Fleet.heard`), at most ``unsure_for`` seconds.  Given work at once,
a robot with a product in its gripper fed that product to a cap station
prepared for RETRIEVE_CAP, which broke it (rcll2016 seed 10 at 672a03b).
"""
from __future__ import annotations

import math
from dataclasses import replace

from ..knowledge import model as M
from ..knowledge.kb import KnowledgeBase
from ..links.agents import wire_id
from ..links.tasks import TaskLink
from ..production.locks import StationLocks

#: kinds of task in which the robot picks a workpiece up
PICKUPS = (M.GET_WORKPIECE, M.RETRIEVE_CAP)


def travel(robot: M.Robot, pos) -> float:
    """Metres from the robot to ``pos`` (0 when either is unknown)."""
    if pos is None or robot.pose is None:
        return 0.0
    return math.hypot(pos[0] - robot.pose[0], pos[1] - robot.pose[1])


def queued_task(kb: KnowledgeBase, number: int) -> M.Task | None:
    """The task sent to robot ``number`` to run after its current one, if any."""
    return next((t for t in kb.open_tasks() if t.state == M.ASSIGNED and t.robot == number
                 and t.after is not None), None)


def next_task(kb: KnowledgeBase, robot: M.Robot) -> M.Task | None:
    """What ``robot`` works at next: the task queued behind its current one, else that."""
    q = queued_task(kb, robot.number)
    return q if q is not None else (kb.tasks.get(robot.task_id) if robot.task_id is not None else None)


class Fleet:
    """See the module doc."""

    def __init__(self, kb: KnowledgeBase, clock, locks: StationLocks, tasks: TaskLink,
                 unsure_for: float = 15.0):
        self.kb = kb
        self.clock = clock
        self.locks = locks
        self.tasks = tasks
        self.unsure_for = unsure_for
        self._idle_since: dict[int, float] = {}
        self._unsure: dict[int, tuple[int, float]] = {}     # robot -> (task id, since)
        self._finishing: dict[int, M.Robot] = {}            # robot -> its copy (:meth:`finishing`)

    def hold_back(self, robot: M.Robot, task: M.Task) -> None:
        """``task`` (a pickup) was taken back from ``robot``: no new work for it until
        its result of ``task`` says what it holds (see the module doc)."""
        self._unsure[robot.number] = (task.id, self.clock.now())

    def took_back(self, task: M.Task) -> None:
        """``task`` (a copy as it was assigned) was cancelled on its robot because its
        product is planned again: a pickup holds the robot back as :meth:`hold_back`."""
        robot = self.kb.robots.get(task.robot) if task.robot is not None else None
        if robot is not None and task.kind in PICKUPS:
            self.hold_back(robot, task)

    def heard(self, number: int, task_id: int) -> None:
        """Robot ``number``'s final result of task ``task_id`` arrived."""
        if self._unsure.get(number, (None,))[0] == task_id:
            del self._unsure[number]

    def unsure(self, robot: M.Robot) -> bool:
        """Is what ``robot`` holds unknown (a pickup taken back, its result not heard)?"""
        got = self._unsure.get(robot.number)
        return got is not None and self.clock.now() - got[1] < self.unsure_for

    def idle_for(self) -> float:
        """Seconds the robot idle longest (no work, empty gripper; parking is no work)
        has been so; called once a tick, after the assignment round."""
        now = self.clock.now()
        idle = {r.number for r in self.available_robots() if not r.holding}
        self._idle_since = {n: self._idle_since.get(n, now) for n in idle}
        return max((now - t for t in self._idle_since.values()), default=0.0)

    def idle_robots(self) -> list[M.Robot]:
        """Robots without a task (a parking robot has one: see :meth:`available_robots`)."""
        return [r for r in self.kb.active_robots() if r.task_id is None]

    def parking_task(self, robot: M.Robot) -> M.Task | None:
        """The GO_TO task ``robot`` is driving, if it is parking."""
        t = self.kb.tasks.get(robot.task_id) if robot.task_id is not None else None
        return t if t is not None and t.kind == M.GO_TO and t.state == M.ASSIGNED else None

    def available_robots(self) -> list[M.Robot]:
        """Robots that may get work: idle ones and parking ones."""
        return [r for r in self.kb.active_robots() if not self.unsure(r)
                and (r.task_id is None or self.parking_task(r) is not None)]

    def near_the_end(self, positions: dict, near: float) -> list[tuple[M.Robot, M.Task]]:
        """Robots that may be given their next task before their current one ends, with
        that task: robots of rll-bt (they hold such a task until it may start) whose latest
        status says they run it, within ``near`` metres of its station, nothing queued yet."""
        out = []
        for r in self.kb.active_robots():
            t = self.kb.tasks.get(r.task_id) if r.task_id is not None else None
            pos = positions.get(t.machine) if t is not None else None
            if (t is None or pos is None or t.state != M.ASSIGNED or r.state != "BUSY" or self.unsure(r)
                    or self.tasks.codec.running.get(r.number) != wire_id(t)       # its status: it runs t
                    or not self.tasks.codec.speaks_rllbt(r) or travel(r, pos) > near
                    or queued_task(self.kb, r.number) is not None):
                continue
            out.append((r, t))
        return out

    def finishing(self, positions: dict, near: float) -> list[M.Robot]:
        """Robots :meth:`near_the_end` of a task that leaves the gripper empty, each as a
        copy standing at its task's station with an empty gripper, as it will be;
        :meth:`assign` queues a task given to such a copy behind the robot's current one."""
        out = [replace(r, pose=(float(positions[t.machine][0]), float(positions[t.machine][1]), 0.0),
                       holding=None, task_id=None)
               for r, t in self.near_the_end(positions, near) if t.carry or t.kind == M.RETRIEVE_CAP]
        self._finishing = {r.number: r for r in out}
        return out

    def queue(self, task: M.Task, robot: M.Robot) -> None:
        """Send ``task`` to ``robot`` to run once its current task succeeded."""
        task.after = robot.task_id
        self._hand_over(task, robot.number)

    def settle_queued(self) -> list[M.Task]:
        """Queued tasks whose predecessor is no longer its robot's assigned task (cancelled,
        taken back, the robot dropped, or its result in: :meth:`after_result`) go back to
        the pool; returns them.  The robot drops such a task itself (its predecessor did
        not succeed, as far as it knows) or has it cancelled (:meth:`back_to_pool`'s caller)."""
        out = []
        for t in self.kb.open_tasks():
            if t.state != M.ASSIGNED or t.after is None:
                continue
            before = self.kb.tasks.get(t.after)
            if before is None or before.state != M.ASSIGNED or before.robot != t.robot:
                self._unqueue(t, f"task {t.after} before it ended otherwise")
                out.append(t)
        return out

    def after_result(self, robot: M.Robot, task: M.Task) -> M.Task | None:
        """``task``'s result from ``robot`` was booked: the task queued behind it starts
        (the robot starts it once ``task`` succeeded) or goes back to the pool."""
        nxt = queued_task(self.kb, robot.number)
        if nxt is None or nxt.after != task.id:
            return None
        if task.state != M.DONE or robot.task_id is not None or robot.status != M.ACTIVE:
            self._unqueue(nxt, f"task {task.id} before it did not succeed")
            return None
        nxt.after, nxt.assigned_at = None, self.clock.now()
        if nxt.carry:
            nxt.holder = robot.number           # it carries what ``task`` picked up
        self.kb.save_task(nxt)
        robot.task_id = nxt.id
        self.kb.save_robot(robot)
        return nxt

    def _unqueue(self, task: M.Task, why: str) -> None:
        if task.carry and task.params.get("carry_from") is not None:
            task.holder = None                  # its pickup failed: whoever picks up again carries
        self.tasks.cancel(task, why)            # (the robot drops it itself; a cancel makes sure)
        self.back_to_pool(task, why)

    def assign(self, task: M.Task, robot: M.Robot) -> None:
        """Give ``task`` to ``robot`` (which stops parking); to a copy :meth:`finishing`
        made: queue it behind that robot's current task."""
        real = self.kb.robots.get(robot.number)
        if robot is self._finishing.get(robot.number) and real is not None and real.task_id is not None:
            del self._finishing[robot.number]
            self.queue(task, real)              # (its current task stays the robot's)
            return
        park = self.parking_task(robot)
        if park is not None and park is not task:
            park.state, park.finished_at = M.CANCELLED, self.clock.now()
            self.kb.save_task(park)
            self.tasks.cancel(park, f"task {task.id} for this robot")
        task.after = None                       # (a task once queued and back in the pool runs now)
        self._hand_over(task, robot.number)
        robot.task_id = task.id
        self.kb.save_robot(robot)

    def _hand_over(self, task: M.Task, number: int) -> None:
        task.state, task.robot = M.ASSIGNED, number
        task.assigned_at, task.attempts = self.clock.now(), task.attempts + 1
        task.prepared_at = None
        self.locks.acquire(task)
        self.kb.save_task(task)
        self.tasks.send(task)

    def assign_explore(self, robot: M.Robot, zone: int) -> M.Task:
        """A new EXPLORE_ZONE task of ``zone`` for ``robot``."""
        t = M.Task(self.kb.next_id("task"), M.EXPLORE_ZONE, {"zone": int(zone)},
                   created=self.clock.now())
        self.assign(t, robot)
        return t

    def back_to_pool(self, task: M.Task, why: str) -> None:
        """An assigned task is PENDING again, for any robot (an exploration task is
        cancelled instead: exploration picks a fresh zone)."""
        task.state, task.robot, task.assigned_at, task.prepared_at = M.PENDING, None, None, None
        task.after, task.error = None, why
        self.kb.save_task(task)
        if task.kind == M.EXPLORE_ZONE:
            task.state = M.CANCELLED        # exploration picks a fresh zone instead
            self.kb.save_task(task)
