"""The dispatcher: ready tasks to idle robots, PrepareMachine at the right moment,
results, and robots that drop out.

- A production task is *ready* when its predecessors are DONE, its station
  locks are free (or held by its own product), its station is neither
  BROKEN nor DOWN, the game is RUNNING in PRODUCTION, the station can take
  its workpiece (:mod:`.feeding`), a delivery's robot would reach the DS
  when the order's window opens, a stored product's retrieval is not before
  its ``not_before`` (shortly before the window), a ring mount's slide holds the bases its
  colour costs (:mod:`.slides`), and a cap retrieval's product has started
  its last ring mount that does not need the cap-less base (:mod:`.caps`).
- A robot left holding a workpiece whose next step is not ready is *stuck*;
  pickups that would leave one more robot stuck wait while ``robots - 1``
  are (``robots - 2``, but one of two, for a new base from the BS), so that a
  robot stays free to fetch what the held workpieces wait for.
- Carry tasks go to the robot holding the workpiece; the others are matched
  to idle robots with empty grippers by travel distance plus ``urgency``
  times the seconds left until the order's window closes (an optimal
  assignment, ``scipy.optimize.linear_sum_assignment``), earlier products
  first on ties.  Locks are taken at assignment.
- PrepareMachine is sent for an assigned task once its robot is within
  ``prepare_distance`` metres of the station or ``prepare_lead`` seconds
  away (``retrieve_lead`` for a storage station's RETRIEVE, which takes that
  long to bring the workpiece out), the station is IDLE and the game
  RUNNING; resent after ``prepare_retry`` seconds if the station did not
  leave IDLE.
- An idle robot standing in front of a station (see :mod:`.parking`) is sent
  to a free spot (a GO_TO task).  A parking robot counts as idle: real work
  cancels its GO_TO.  A failed GO_TO waits ``park_retry`` seconds.
- A failed discard (without a station) is not resent at once: the robot
  waits ``discard_backoff`` seconds (doubling per failure in a row, at most
  4x) and may be parked meanwhile, so the next try happens somewhere else.
- A task whose station goes BROKEN or DOWN before its PrepareMachine went
  out, its robot carrying nothing for it, goes back to the pool and the
  robot is free again (:meth:`Dispatcher.release_unusable`); tasks that
  free a stuck robot (the pending predecessors of its next step) are
  preferred by ``unblock`` metres in the assignment.
- A robot silent for ``heartbeat_timeout`` seconds is dropped: its task goes
  back to the pool (or, if it carried a workpiece, the product is repaired).

The dispatcher does not send anything itself: it appends to :attr:`outbox`
(``("task", Task)``, ``("cancel", Task, reason)``, ``("prepare", Task)``)
and the server turns these into messages.
"""
from __future__ import annotations

import logging
import math
from dataclasses import dataclass

import numpy as np
from scipy.optimize import linear_sum_assignment

from . import parking
from .feeding import FeedMonitor
from .holding import HoldingMixin
from .knowledge import model as M
from .knowledge.kb import KnowledgeBase
from .production import ProductionManager

log = logging.getLogger("teamserver.dispatch")

UNUSABLE_STATES = ("BROKEN", "DOWN")
#: errors after which the same step is simply tried again
RETRY_ERRORS = {"NAVIGATION_FAILED", "LOCALISATION_LOST", "MACHINE_NOT_FOUND", "ALIGN_FAILED", "SENSOR_LOST",
                "GRAB_FAILED", "TIMEOUT", "NOT_RUNNING", "MACHINE_BROKEN", "NONE"}


@dataclass
class DispatchConfig:
    """Seconds, metres and counts that steer the dispatcher."""

    heartbeat_timeout: float = 10.0
    prepare_distance: float = 1.5
    prepare_lead: float = 3.0
    retrieve_lead: float = 12.0     # ... a storage station's RETRIEVE this many seconds away
    prepare_retry: float = 6.0
    speed: float = 0.5
    max_attempts: int = 3
    deliver_early: float = 60.0     # at most this long before the window a delivery starts
    deliver_margin: float = 5.0     # ... and this long more than the drive to the DS takes
    window_margin: float = 1.0      # the DS is prepared this long after the window opened
    feed_confirm: float = 10.0      # a fed station reports the workpiece within this time
    pickup_time: float = 30.0       # a pickup's drive and grab, for "ready once held"
    urgency: float = 0.01           # metres of drive a second of an order's slack is worth
    unblock: float = 20.0           # metres of drive that freeing a stuck robot is worth
    park: bool = True
    park_retry: float = 15.0
    discard_backoff: float = 5.0


class Dispatcher(HoldingMixin):
    def __init__(self, kb: KnowledgeBase, production: ProductionManager, clock,
                 config: DispatchConfig | None = None):
        config = config if config is not None else DispatchConfig()
        self.kb = kb
        self.production = production
        self.clock = clock
        self.config = config
        self.outbox: list[tuple] = []
        self.feeds = FeedMonitor(kb, production, clock, config.feed_confirm)
        self.parking = parking.ParkingConfig()
        self._park_wait: dict[int, float] = {}       # robot -> server time it may park again
        self._discard_wait: dict[int, float] = {}    # robot -> server time it may discard again
        self._discard_fails: dict[int, int] = {}     # robot -> failed discards in a row

    # -- robots ----------------------------------------------------------------------
    def idle_robots(self) -> list[M.Robot]:
        """Robots without a task (a parking robot has one: see :meth:`available_robots`)."""
        return [r for r in self.kb.active_robots() if r.task_id is None]

    def parking_task(self, robot: M.Robot) -> M.Task | None:
        """The GO_TO task ``robot`` is driving, if it is parking."""
        t = self.kb.tasks.get(robot.task_id) if robot.task_id is not None else None
        return t if t is not None and t.kind == M.GO_TO and t.state == M.ASSIGNED else None

    def available_robots(self) -> list[M.Robot]:
        """Robots that may get work: idle ones and parking ones."""
        return [r for r in self.kb.active_robots()
                if r.task_id is None or self.parking_task(r) is not None]

    def check_heartbeats(self) -> list[M.Robot]:
        """Drop robots silent for too long; returns the ones dropped now."""
        now = self.clock.now()
        dropped = []
        for r in list(self.kb.robots.values()):
            if r.status == M.ACTIVE and now - r.last_heartbeat > self.config.heartbeat_timeout:
                self.drop(r, f"no heartbeat for {now - r.last_heartbeat:.1f} s")
                dropped.append(r)
        return dropped

    def drop(self, robot: M.Robot, why: str) -> None:
        log.warning("robot %d dropped: %s", robot.number, why)
        robot.status = M.LOST
        task = self.kb.tasks.get(robot.task_id) if robot.task_id is not None else None
        robot.task_id = None
        if robot.holding:
            wp = self.kb.workpieces.get(robot.holding)
            if wp is not None:
                wp.location = "gone"
                self.kb.save_workpiece(wp)
                self.production.needs_repair(wp.product, f"robot {robot.number} lost with it")
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
                self.production.needs_repair(task.product, f"robot {robot.number} lost")
            else:
                self._back_to_pool(task, f"robot {robot.number} lost")
        # carry tasks bound to this robot can no longer be done by it
        for t in self.kb.open_tasks():
            if t.holder == robot.number and t.state == M.PENDING:
                self.production.needs_repair(t.product, f"robot {robot.number} lost")

    def release_unusable(self) -> list[M.Task]:
        """Assigned tasks whose station went BROKEN or DOWN before their
        PrepareMachine went out, and whose robot carries nothing for it, go back
        to the pool: the robot is told to stop and is free for other work
        instead of waiting at the station.  Returns the tasks released."""
        out = []
        for t in self.kb.open_tasks():
            if (t.state != M.ASSIGNED or t.carry or t.prepared_at is not None
                    or t.kind in (M.GO_TO, M.EXPLORE_ZONE) or self.station_usable(t.machine)):
                continue
            robot = self.kb.robots.get(t.robot) if t.robot is not None else None
            state = self.kb.stations[t.machine].state
            self.outbox.append(("cancel", t, f"{t.machine} is {state}"))
            self._back_to_pool(t, f"{t.machine} {state} before it was prepared")
            if robot is not None and robot.task_id == t.id:
                robot.task_id = None
                self.kb.save_robot(robot)
            log.info("task %d released: %s is %s", t.id, t.machine, state)
            out.append(t)
        return out

    def _back_to_pool(self, task: M.Task, why: str) -> None:
        task.state, task.robot, task.assigned_at, task.prepared_at = M.PENDING, None, None, None
        task.error = why
        self.kb.save_task(task)
        if task.kind == M.EXPLORE_ZONE:
            task.state = M.CANCELLED        # exploration picks a fresh zone instead
            self.kb.save_task(task)

    # -- readiness -----------------------------------------------------------------------
    def station_usable(self, machine: str | None) -> bool:
        if machine is None:
            return True
        st = self.kb.stations.get(machine)
        return st is None or st.state not in UNUSABLE_STATES

    def ready(self, task: M.Task, game_time: float | None) -> bool:
        if task.state != M.PENDING or task.kind == M.EXPLORE_ZONE:
            return False
        if game_time is None:
            return False
        for d in task.deps:
            dep = self.kb.tasks.get(d)
            if dep is None or dep.state != M.DONE:
                return False
        if not self.production.lock_free(task):
            return False
        if not self.station_usable(task.machine):
            return False
        if not self.feeds.accepts(task):
            return False
        if task.kind == M.DELIVER and game_time < self.deliver_from(task):
            return False
        if task.kind != M.DELIVER and game_time < float(task.params.get("not_before", 0.0)):
            return False                # a stored product is retrieved shortly before its window
        if not self.production.slide_ready(task):
            return False                # the ring station would break for want of bases
        # a CS holding a cap cannot retrieve another
        return not (task.kind == M.RETRIEVE_CAP and (self.production.cap_buffer.get(task.machine)
                                                     or not self.production.cap_due(task)))

    def deliver_from(self, task: M.Task) -> float:
        """Game time from which a delivery may start: its robot reaches the DS when
        the order's window opens (never more than ``deliver_early`` s before it)."""
        nb = float(task.params.get("not_before", 0.0))
        robot = self.kb.robots.get(task.holder) if task.holder is not None else None
        pos = self.production.positions().get(task.machine) if robot is not None else None
        drive = self.travel(robot, pos) / self.config.speed if robot is not None else 0.0
        return nb - min(drive + self.config.deliver_margin, self.config.deliver_early)

    # -- assignment ------------------------------------------------------------------------
    def assign(self, game_time: float | None) -> list[M.Task]:
        """Give ready tasks to idle robots; returns the tasks assigned now."""
        idle = {r.number: r for r in self.available_robots()}
        if not idle:
            return []
        self.production.adopt_free_caps()
        self.production.top_up_slides()
        ready = [t for t in self.kb.open_tasks() if self.ready(t, game_time)]
        assigned: list[M.Task] = []
        # carry tasks: their holder, if idle
        for t in sorted(ready, key=lambda t: t.id):
            if t.carry:
                r = idle.get(t.holder) if t.holder is not None else None
                if r is not None and self.production.lock_free(t):
                    self._assign(t, r)
                    assigned.append(t)
                    del idle[r.number]
        free = [r for r in idle.values() if not r.holding]
        pool = [t for t in ready if not t.carry]
        if not free or not pool:
            return assigned
        # robots must stay able to fetch what the held workpieces wait for
        stuck, n = self.stuck(game_time), len(self.kb.active_robots())
        blocking = {t.id: self.hold_limit(t, n) for t in pool if self.blocks(t, game_time)}
        pool = [t for t in pool if stuck < blocking.get(t.id, n)]
        if not pool:
            return assigned
        positions = self.production.positions()
        frees = self.unblocking(game_time) if stuck else set()
        cost = np.zeros((len(free), len(pool)))
        for i, r in enumerate(free):
            for j, t in enumerate(pool):
                cost[i, j] = (self.travel(r, positions.get(t.machine)) + 1e-3 * _age(t)
                              + self.config.urgency * self._slack(t, game_time)
                              - self.config.unblock * (t.id in frees))
        rows, cols = linear_sum_assignment(cost)
        for i, j in sorted(zip(rows, cols), key=lambda ij: cost[ij[0], ij[1]]):
            t, r = pool[j], free[i]
            if not self.production.lock_free(t):
                continue                    # another assignment just took the station
            if t.id in blocking:
                if stuck >= blocking[t.id]:
                    continue                # the next tick matches this robot anew
                stuck += 1
            self._assign(t, r)
            assigned.append(t)
        return assigned

    def _slack(self, task: M.Task, game_time: float | None) -> float:
        """Game seconds until the end of the window of ``task``'s order (0 for work
        that only clears a station: it goes first)."""
        p = self.kb.products.get(task.product or "")
        o = self.kb.orders.get(p.order_id) if p is not None else None
        if o is None or game_time is None:
            return 0.0
        return min(max(o.end - game_time, 0.0), float(self.kb.profile.phases.production))

    def travel(self, robot: M.Robot, pos) -> float:
        """Metres from the robot to ``pos`` (0 when either is unknown)."""
        if pos is None or robot.pose is None:
            return 0.0
        return math.hypot(pos[0] - robot.pose[0], pos[1] - robot.pose[1])

    def _assign(self, task: M.Task, robot: M.Robot) -> None:
        park = self.parking_task(robot)
        if park is not None and park is not task:
            park.state, park.finished_at = M.CANCELLED, self.clock.now()
            self.kb.save_task(park)
            self.outbox.append(("cancel", park, f"task {task.id} for this robot"))
        task.state, task.robot = M.ASSIGNED, robot.number
        task.assigned_at, task.attempts = self.clock.now(), task.attempts + 1
        task.prepared_at = None
        self.production.acquire(task)
        self.kb.save_task(task)
        robot.task_id = task.id
        self.kb.save_robot(robot)
        self.outbox.append(("task", task))

    def assign_explore(self, robot: M.Robot, zone: int) -> M.Task:
        t = M.Task(self.kb.next_id("task"), M.EXPLORE_ZONE, {"zone": int(zone)},
                   created=self.clock.now())
        self._assign(t, robot)
        return t

    # -- parking -------------------------------------------------------------------------------
    def park(self) -> list[M.Task]:
        """Send idle robots that stand in front of a station to a free spot
        (GO_TO tasks); returns the tasks assigned now."""
        if not self.config.park:
            return []
        now = self.clock.now()
        profile = self.kb.profile
        approach, centres = parking.station_points(self.kb, profile)
        if not approach:
            return []
        out = []
        for r in self.idle_robots():
            if r.pose is None or self._park_wait.get(r.number, -math.inf) > now:
                continue
            if not parking.in_the_way(r.pose, approach, self.parking):
                continue
            spot = parking.parking_spot(r.pose, profile, approach, centres,
                                        self._other_robots(r), self.parking)
            if spot is None:
                self._park_wait[r.number] = now + self.config.park_retry
                continue
            theta = math.atan2(spot[1] - r.pose[1], spot[0] - r.pose[0])
            t = M.Task(self.kb.next_id("task"), M.GO_TO,
                       {"x": spot[0], "y": spot[1], "theta": theta}, created=now)
            self._assign(t, r)
            log.info("robot %d parks at (%.2f, %.2f), out of the stations' way", r.number, *spot)
            out.append(t)
        return out

    def _other_robots(self, robot: M.Robot) -> list[tuple[float, float]]:
        """Where the other robots stand and where they park."""
        pts = [(o.pose[0], o.pose[1]) for o in self.kb.active_robots()
               if o.number != robot.number and o.pose is not None]
        pts += [(float(t.params["x"]), float(t.params["y"])) for t in self.kb.open_tasks()
                if t.kind == M.GO_TO and t.robot != robot.number]
        return pts

    # -- PrepareMachine timing -----------------------------------------------------------------
    def prepare(self, running_production: bool, game_time: float | None = None
                ) -> list[M.Task]:
        """Send the PrepareMachine of assigned tasks whose robot is about to arrive
        (a station already waiting with the same instruction is adopted, see
        :mod:`.feeding`); a DS only once the order's window is open (``game_time``,
        None: not checked).  Also the late prepares of feeds finished before theirs
        could go out."""
        if not running_production:
            return []
        sent = []
        now = self.clock.now()
        positions = self.production.positions()
        for t in self.kb.open_tasks():
            if t.state != M.ASSIGNED or not t.prepare:
                continue
            st = self.kb.stations.get(t.prepare["machine"])
            state = st.state if st is not None else "IDLE"
            if t.prepared_at is not None:
                # resend only if the station never reacted (a lost datagram)
                if st is None or st.since >= t.prepared_at or state != "IDLE" or \
                        now - t.prepared_at < self.config.prepare_retry:
                    continue
            elif state == "PREPARED" and self.feeds.adoptable(t):
                t.prepared_at = now             # it waits with our instruction already
                self.kb.save_task(t)
                self.feeds.sent(t)
                log.info("task %d adopts %s waiting with %s", t.id, st.name, t.prepare)
                continue
            elif state != "IDLE":
                continue
            if not self._window_open(t, game_time):
                continue
            robot = self.kb.robots.get(t.robot)
            if robot is None:
                continue
            pos = positions.get(t.prepare["machine"])
            if robot.pose is not None and pos is not None:
                d = self.travel(robot, pos)
                lead = self.config.retrieve_lead if t.prepare.get("ss", {}).get(
                    "operation") == "RETRIEVE" else self.config.prepare_lead
                if d > self.config.prepare_distance and d / self.config.speed > lead:
                    continue
            self._send_prepare(t, now)
            sent.append(t)
        for t in self.feeds.late():
            st = self.kb.stations.get(t.prepare["machine"])
            if st is not None and st.state == "IDLE" and self._window_open(t, game_time):
                self._send_prepare(t, now)
                self.feeds.late_sent(t)
                sent.append(t)
        return sent

    def _window_open(self, task: M.Task, game_time: float | None) -> bool:
        """A delivery's DS is prepared only inside the order's window."""
        if task.kind != M.DELIVER or game_time is None:
            return True
        return game_time >= float(task.params.get("not_before", 0.0)) + self.config.window_margin

    def _send_prepare(self, task: M.Task, now: float) -> None:
        task.prepared_at = now
        self.kb.save_task(task)
        self.feeds.sent(task)
        self.outbox.append(("prepare", task))

    # -- results -------------------------------------------------------------------------
    def on_result(self, robot_number: int, task_id: int, status: str, error: str = "NONE",
                  holding: bool | None = None, text: str = "") -> None:
        """A TaskResult: ``status`` RUNNING/SUCCEEDED/FAILED/CANCELLED, ``error`` the
        ErrorCode name, ``holding`` whether the gripper holds something afterwards
        (None: not said)."""
        task = self.kb.tasks.get(task_id)
        robot = self.kb.robots.get(robot_number)
        if task is None or robot is None:
            return
        if task.robot != robot_number or task.state != M.ASSIGNED:
            if status == "RUNNING" and task.robot != robot_number:
                self.outbox.append(("cancel", task, "task no longer yours"))
            return
        if status == "RUNNING":
            return
        robot.task_id = None
        task.finished_at = self.clock.now()
        if task.kind == M.GO_TO:
            task.state = M.DONE if status == "SUCCEEDED" else M.FAILED
            task.error = None if status == "SUCCEEDED" else (f"{error}: {text}" if text else error)
            self.kb.save_task(task)
            self.kb.save_robot(robot)
            if status != "SUCCEEDED":
                self._park_wait[robot.number] = self.clock.now() + self.config.park_retry
            return
        if status == "FAILED" and self.feeds.took(task):
            log.info("task %d failed (%s), but %s took its workpiece: done", task.id, error,
                     task.machine)
            status = "SUCCEEDED"
        if task.kind == M.DISCARD and status != "CANCELLED":
            self._discard_outcome(robot, status == "SUCCEEDED")
        if status != "CANCELLED":
            self.production.health.outcome(task, status == "SUCCEEDED", error, self.clock.now())
        if status == "SUCCEEDED":
            task.state = M.DONE
            self.kb.save_task(task)
            if task.kind == M.EXPLORE_ZONE:
                self.kb.mark_visited(int(task.params["zone"]), self.clock.now())
            else:
                self.production.task_done(task, robot)
                self.feeds.finished(task)
            self.kb.save_robot(robot)
            return
        task.error = f"{error}: {text}" if text else error
        if status == "CANCELLED" or task.kind == M.EXPLORE_ZONE:
            task.state = M.CANCELLED if status == "CANCELLED" else M.FAILED
            self.kb.save_task(task)
            if task.kind != M.EXPLORE_ZONE:
                self.production.needs_repair(task.product, f"task {task.id} cancelled")
            self.kb.save_robot(robot)
            return
        self._failed(task, robot, error, holding)

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
        self.kb.save_robot(robot)
        if error == "MACHINE_BROKEN" and task.machine:
            st = self.kb.stations.get(task.machine)
            if st is not None and st.state == "BROKEN":
                self.production.station_broke(task.machine)
        retry = (not lost and error in RETRY_ERRORS and task.attempts < self.config.max_attempts
                 and not (task.kind == M.DISCARD and not task.machine)
                 and self.production.health.usable(task, self.clock.now()))
        if retry:
            again = self.production.retry(task)
            log.info("task %d failed (%s), trying again as %d", task.id, error, again.id)
            if again.carry:
                again.holder = robot.number
                self.kb.save_task(again)
            return
        task.state = M.FAILED
        self.kb.save_task(task)
        self.production.needs_repair(task.product, f"task {task.id} {task.kind} failed: {error}")

    # -- orphans ---------------------------------------------------------------------------------
    def discard_orphans(self) -> list[M.Task]:
        """Idle robots holding a workpiece no open task will take: discard it."""
        bound = {t.holder for t in self.kb.open_tasks() if t.carry}
        now = self.clock.now()
        out = []
        for r in self.idle_robots():
            if self._discard_wait.get(r.number, -math.inf) > now:
                continue                     # a discard just failed: not again at once
            if r.holding and r.number not in bound:
                out.append(self.production.discard_for(r))
        return out

    def _discard_outcome(self, robot: M.Robot, ok: bool) -> None:
        """Count failed discards in a row and set the robot's wait before the next."""
        if ok:
            self._discard_fails.pop(robot.number, None)
            self._discard_wait.pop(robot.number, None)
            return
        n = self._discard_fails.get(robot.number, 0) + 1
        self._discard_fails[robot.number] = n
        self._discard_wait[robot.number] = self.clock.now() + \
            self.config.discard_backoff * min(2 ** (n - 1), 4)


def _age(task: M.Task) -> float:
    return float(task.id)
