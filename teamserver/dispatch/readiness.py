"""When a task may go: the readiness policy of the dispatcher.

A production task is *ready* when

- its predecessors are DONE and its station locks are free (or held by its
  own product: :mod:`teamserver.production.locks`);
- its station is neither BROKEN nor DOWN (:meth:`Readiness.station_usable`);
- no robot may still run it: a task taken back from a robot (its station
  went down, :mod:`.dropouts`) waits until that robot has provably stopped
  it (acknowledged the cancel or sent a result,
  :meth:`~teamserver.links.tasks.TaskLink.stop_owed`), and no robot's latest
  status says it runs the task
  (:meth:`~teamserver.links.tasks.TaskLink.said_running`), unless that robot has been silent
  past its lease (``heartbeat_timeout`` and every lease granted to it over, as a dropped
  robot: :mod:`teamserver.links.leases`), so that a cancel lost in a cut
  never lets two robots run one task (:meth:`Readiness.held_by`); nor, at the
  same station, a task planned anew in place of a cancelled one (a product
  planned again gets new tasks under new ids: :meth:`Readiness.station_held_by`);
- the station can take its workpiece (:mod:`teamserver.production.feeding`);
- a delivery's robot would reach the DS when the order's window opens
  (:meth:`Readiness.deliver_from`); a stored product's retrieval is not
  before its ``not_before`` (shortly before the window);
- a ring mount's slide holds the bases its colour costs
  (:mod:`teamserver.production.slides`);
- a cap retrieval's station holds no cap and its product has started its
  last ring mount that does not need the cap-less base
  (:mod:`teamserver.production.caps`);
- while production goes on beside exploration (2017+), neither it nor any
  other step of its product is at a station not found yet
  (:attr:`Readiness.unfound`, set by the team server to
  :meth:`~teamserver.exploration.explorer.Explorer.unfound`): a robot would
  not know where to drive, or would hold a workpiece until it does.

A delivery's DS is prepared only inside the order's window
(:meth:`Readiness.window_open`).  A rule about when a station may be used
(prepare before feeding, time-outs of a prepared station, costs of
storing) goes here or into the collaborator it is about.
"""
from __future__ import annotations

from collections.abc import Callable

from ..knowledge import model as M
from ..knowledge.kb import KnowledgeBase
from ..links.tasks import TaskLink
from ..production.caps import CapBuffers, Caps
from ..production.feeding import FeedMonitor
from ..production.locks import StationLocks
from ..production.slides import Slides
from ..production.world import PlanningWorld
from .config import DispatchConfig
from .fleet import travel

UNUSABLE_STATES = ("BROKEN", "DOWN")


class Readiness:
    """See the module doc."""

    def __init__(self, kb: KnowledgeBase, locks: StationLocks, feeds: FeedMonitor,
                 slides: Slides, caps: Caps, buffers: CapBuffers, world: PlanningWorld,
                 config: DispatchConfig, tasks: TaskLink | None = None, clock=None):
        self.kb = kb
        self.locks = locks
        self.feeds = feeds
        self.slides = slides
        self.caps = caps
        self.buffers = buffers
        self.world = world
        self.config = config
        self.tasks = tasks
        self.clock = clock
        #: our stations not found yet (exploring beside production: see the module doc)
        self.unfound: Callable[[], frozenset[str]] = frozenset

    def held_by(self, task: M.Task) -> int | None:
        """The robot that may still run ``task`` (cancelled on it, its stop not proven,
        heard within its lease), or None."""
        if self.tasks is None:
            return None
        owed, said = self.tasks.stop_owed(task.id), self.tasks.said_running(task.id)
        for number in (owed, said):
            if number is None:
                continue
            if self._heard(number):
                return number
            if number == owed:
                self.tasks.stopped(number, task.id)     # silent past its lease: it has stopped
        return None

    def station_held_by(self, task: M.Task) -> int | None:
        """A robot that may still run another task at ``task``'s station, cancelled on
        it (its stop not proven, heard within its lease), or None: a product planned
        again (:mod:`teamserver.production.repair`) has new tasks under new ids, and a
        new pickup at the output the cancelled one was fetching from must not send a
        second robot there while the first may still grab the workpiece."""
        if self.tasks is None or task.machine is None:
            return None
        for tid, number in self.tasks.stops_owed().items():
            other = self.kb.tasks.get(tid)
            if tid == task.id or other is None or other.machine != task.machine:
                continue
            if self._heard(number):
                return number
            self.tasks.stopped(number, tid)             # silent past its lease: it has stopped
        return None

    def _heard(self, number: int) -> bool:
        """Robot ``number`` is active and heard within its lease."""
        robot = self.kb.robots.get(number)
        return robot is not None and robot.status == M.ACTIVE and (
            self.clock is None or not self.tasks.past_lease(robot, self.config.heartbeat_timeout, self.clock.now()))

    def station_usable(self, machine: str | None) -> bool:
        if machine is None:
            return True
        st = self.kb.stations.get(machine)
        return st is None or st.state not in UNUSABLE_STATES

    def ready(self, task: M.Task, game_time: float | None, but: str | None = None, done=()) -> bool:
        """May ``task`` go now (see the module doc)?  ``but``: as if product ``but``
        had given up its station locks and taken its workpiece out of their outputs;
        ``done``: as if these tasks (ids) were DONE."""
        if task.state != M.PENDING or task.kind == M.EXPLORE_ZONE:
            return False
        if game_time is None:
            return False
        for d in task.deps:
            dep = self.kb.tasks.get(d)
            if dep is None or (dep.state != M.DONE and d not in done):
                return False
        if not self.locks.free_for(task, but):
            return False
        if self._needs_unfound(task):
            return False
        if not self.station_usable(task.machine):
            return False
        if self.held_by(task) is not None or self.station_held_by(task) is not None:
            return False
        if not self.feeds.accepts(task, emptied=but is not None):
            return False
        if task.kind == M.DELIVER and game_time < self.deliver_from(task):
            return False
        if task.kind != M.DELIVER and game_time < float(task.params.get("not_before", 0.0)):
            return False                # a stored product is retrieved shortly before its window
        if not self.slides.slide_ready(task):
            return False                # the ring station would break for want of bases
        # a CS holding a cap cannot retrieve another
        return not (task.kind == M.RETRIEVE_CAP and (self.buffers.owners.get(task.machine)
                                                     or not self.caps.cap_due(task)))

    def _needs_unfound(self, task: M.Task) -> bool:
        """Is ``task``, or an open step of its product, at a station not found yet?"""
        gone = self.unfound()
        if not gone:
            return False
        if task.machine in gone:
            return True
        p = self.kb.products.get(task.product or "")
        return p is not None and any(t.machine in gone for t in self.kb.tasks_of(p.tasks)
                                     if t.state in (M.PENDING, M.ASSIGNED))

    def deliver_from(self, task: M.Task) -> float:
        """Game time from which a delivery may start: its robot reaches the DS when
        the order's window opens (never more than ``deliver_early`` s before it)."""
        nb = float(task.params.get("not_before", 0.0))
        robot = self.kb.robots.get(task.holder) if task.holder is not None else None
        pos = self.world.positions().get(task.machine) if robot is not None else None
        drive = travel(robot, pos) / self.config.speed if robot is not None else 0.0
        return nb - min(drive + self.config.deliver_margin, self.config.deliver_early)

    def window_open(self, task: M.Task, game_time: float | None) -> bool:
        """A delivery's DS is prepared only inside the order's window."""
        if task.kind != M.DELIVER or game_time is None:
            return True
        return game_time >= float(task.params.get("not_before", 0.0)) + self.config.window_margin
