"""PrepareMachine at the right moment.

PrepareMachine is sent for an assigned task once its robot is within
``prepare_distance`` metres of the station or ``prepare_lead`` seconds
away (``retrieve_lead`` for a storage station's RETRIEVE, which takes that
long to bring the workpiece out), the station is IDLE and the game
RUNNING; resent after ``prepare_retry`` seconds if the station did not
leave IDLE.  Under rules that break a machine left PREPARED too long (2025:
its workpiece must reach the middle of the belt within 20 s of the
prepare) a feed's station is prepared only once its robot says it waits
there, docked (RobotStatus ``waiting_at``, the trees' ``wait_station``):
a robot near the station may still need more than 20 s to dock (another
robot at the slide, a re-approach), and a RetrieveCap's robot first takes
the carrier from the shelf.  Either way the robot puts its workpiece only once the refbox
shows the station prepared (the trees' ``wait_station``).  A station
already PREPARED with the task's very instruction is adopted
(:mod:`teamserver.production.feeding`); a DS is prepared only inside the
order's window.
"""
from __future__ import annotations

import logging

from ..knowledge import model as M
from ..knowledge.kb import KnowledgeBase
from ..links.tasks import TaskLink
from ..production.feeding import FeedMonitor, is_feed
from ..production.world import PlanningWorld
from .config import DispatchConfig
from .fleet import travel
from .readiness import Readiness

log = logging.getLogger("teamserver.dispatch")


class Preparer:
    """See the module doc."""

    def __init__(self, kb: KnowledgeBase, clock, readiness: Readiness, feeds: FeedMonitor,
                 world: PlanningWorld, tasks: TaskLink, config: DispatchConfig):
        self.kb = kb
        self.clock = clock
        self.readiness = readiness
        self.feeds = feeds
        self.world = world
        self.tasks = tasks
        self.config = config

    def prepare(self, running_production: bool, game_time: float | None = None
                ) -> list[M.Task]:
        """Send the PrepareMachine of assigned tasks whose robot is about to arrive
        (a station already waiting with the same instruction is adopted, see
        :mod:`teamserver.production.feeding`); a DS only once the order's window is
        open (``game_time``, None: not checked).  Also the late prepares of feeds
        finished before theirs could go out."""
        if not running_production:
            return []
        sent = []
        now = self.clock.now()
        positions = self.world.positions()
        for t in self.kb.open_tasks():
            if t.state != M.ASSIGNED or not t.prepare or t.after is not None:
                continue                # (a queued task: its robot is still at the one before)
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
            if not self.readiness.window_open(t, game_time):
                continue
            robot = self.kb.robots.get(t.robot)
            if robot is None:
                continue
            pos = positions.get(t.prepare["machine"])
            if self.config.stuck_timeout is not None and is_feed(t):
                if not self._at_station(t, robot, pos):
                    continue
            elif robot.pose is not None and pos is not None:
                d = travel(robot, pos)
                lead = self.config.retrieve_lead if t.prepare.get("ss", {}).get(
                    "operation") == "RETRIEVE" else self.config.prepare_lead
                if d > self.config.prepare_distance and d / self.config.speed > lead:
                    continue
            self._send(t, now)
            sent.append(t)
        for t in self.feeds.late():
            st = self.kb.stations.get(t.prepare["machine"])
            if st is not None and st.state == "IDLE" and self.readiness.window_open(t, game_time):
                self._send(t, now)
                self.feeds.late_sent(t)
                sent.append(t)
        return sent

    def _at_station(self, task: M.Task, robot: M.Robot, pos) -> bool:
        """The feed's robot waits docked at its station for the prepare."""
        return robot.waiting_at == task.prepare["machine"]

    def _send(self, task: M.Task, now: float) -> None:
        task.prepared_at = now
        self.kb.save_task(task)
        self.feeds.sent(task)
        self.tasks.prepare(task)
