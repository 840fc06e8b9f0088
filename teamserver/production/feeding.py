"""Did the station take the workpiece?  Feeds, the instruction a station waits
with, and stations left waiting for a workpiece that never came.

A *feed* is a task whose robot puts a workpiece into a station's input for
an instruction the server sent (MountRing, MountCap, RetrieveCap,
Deliver, and a PutWorkpiece into a storage station for STORE).  A robot can
report such a task done while the workpiece never reached the conveyor (it
fell beside it).  The station then stays
PREPARED with our instruction: the refbox accepts no new PrepareMachine
for it until it is fed, so the next robot's workpiece is processed with the
*old* instruction (at the DS: delivered at the old gate).

:class:`FeedMonitor`

- remembers the instruction last sent to each station
  (:meth:`~FeedMonitor.sent`) and tells whether a station is PREPARED with
  it, not yet fed (:meth:`~FeedMonitor.instruction`);
- lets a task use a station only when it can take the workpiece: IDLE or
  about to be (WAIT-IDLE), or already PREPARED with this task's very
  instruction and no other robot on its way to feed it
  (:meth:`~FeedMonitor.accepts`); such a task *adopts* the waiting
  instruction instead of sending it again (:meth:`~FeedMonitor.adoptable`);
- checks every finished feed: the station must report that it took a
  workpiece (:attr:`teamserver.knowledge.model.Station.fed_at`) within ``confirm``
  seconds, else the workpiece is lost and its product repaired
  (:meth:`~FeedMonitor.verify`); a feed a robot reports failed although its
  station took the workpiece counts as done (:meth:`~FeedMonitor.took`);
- keeps feeds finished before their PrepareMachine could go out (a robot at
  the DS before the order's window) so the dispatcher sends it later
  (:meth:`~FeedMonitor.late`);
- feeds a spare base to a station PREPARED with an instruction no task
  needs while a task needs another one, or only tasks whose workpiece is
  still being made need it while another's is ready
  (:meth:`~FeedMonitor.unstick`),
  which brings it back to IDLE; not under rules that break a machine left
  PREPARED (2025: after 20 s), where it is IDLE again after its BROKEN time
  long before a spare base could come, which would then lie on the input of
  an IDLE station for the next prepare to process.

Times are seconds of the server's clock; the state lives in the knowledge
base (``prepared``, ``feeds``, ``late_prepares``, ``flushing``).
"""
from __future__ import annotations

import logging

from ..knowledge import model as M
from ..knowledge.kb import KnowledgeBase
from .cleanup import Cleanup
from .repair import Repairs

log = logging.getLogger("teamserver.production.feeding")

#: (a PutWorkpiece feeds only with a prepare: a storage station's STORE)
FEED_KINDS = (M.MOUNT_RING, M.MOUNT_CAP, M.RETRIEVE_CAP, M.DELIVER, M.PUT_WORKPIECE)
#: station states in which it takes a new PrepareMachine now or in a moment
ACCEPTING = ("IDLE", "WAIT-IDLE")


def is_feed(task: M.Task) -> bool:
    return task.kind in FEED_KINDS and bool(task.prepare)


class FeedMonitor:
    """See the module doc.  ``repairs`` undoes a feed the station never took;
    ``cleanup`` makes the products that feed a spare base."""

    def __init__(self, kb: KnowledgeBase, clock, repairs: Repairs, cleanup: Cleanup,
                 confirm: float = 10.0):
        self.kb = kb
        self.clock = clock
        self.repairs = repairs
        self.cleanup = cleanup
        self.confirm = confirm

    # -- the instruction a station waits with ------------------------------------------
    def sent(self, task: M.Task) -> None:
        """``task``'s PrepareMachine went out (or was adopted) now."""
        prepared = dict(self.kb.get("prepared") or {})
        prepared[task.prepare["machine"]] = {"prepare": task.prepare, "at": self.clock.now(),
                                             "task": task.id}
        self.kb.set("prepared", prepared)

    def instruction(self, machine: str) -> dict | None:
        """The instruction ``machine`` is PREPARED with and not yet fed, if we sent it
        (None while a robot's feed there is still being checked: it may yet arrive)."""
        st = self.kb.stations.get(machine)
        rec = (self.kb.get("prepared") or {}).get(machine)
        if st is None or rec is None or st.state != "PREPARED" or st.fed_at >= rec["at"]:
            return None
        if self._checking(machine):
            return None
        return rec["prepare"]

    def _checking(self, machine: str) -> bool:
        for key in self.kb.get("feeds") or {}:
            t = self.kb.tasks.get(int(key))
            if t is not None and t.machine == machine:
                return True
        return False

    def _owner(self, machine: str) -> M.Task | None:
        """The assigned task on its way to feed ``machine``'s waiting instruction."""
        rec = (self.kb.get("prepared") or {}).get(machine)
        t = self.kb.tasks.get(rec["task"]) if rec else None
        if t is not None and t.state == M.ASSIGNED and t.prepared_at is not None:
            return t
        return None

    def adoptable(self, task: M.Task) -> bool:
        """The station waits with exactly ``task``'s instruction and nobody else feeds it."""
        machine = task.prepare["machine"]
        owner = self._owner(machine)
        return (self.instruction(machine) == task.prepare
                and (owner is None or owner.id == task.id))

    def accepts(self, task: M.Task, emptied: bool = False) -> bool:
        """Can ``task``'s station take its workpiece (see the module doc)?  True for
        tasks that feed nothing.  ``emptied``: as if the workpiece in the station's
        output were taken (READY-AT-OUTPUT: the station is IDLE a moment after)."""
        if not is_feed(task):
            return True
        machine = task.prepare["machine"]
        if any(t.prepare["machine"] == machine for t in self.late() if t.id != task.id):
            return False                # a workpiece waits in its input for a prepare
        st = self.kb.stations.get(machine)
        if st is None or st.state in ACCEPTING or (emptied and st.state == "READY-AT-OUTPUT"):
            return True
        return st.state == "PREPARED" and self.adoptable(task)

    def took(self, task: M.Task) -> bool:
        """Has ``task``'s station taken a workpiece since its prepare (a robot may
        report a feed failed that got there: it failed backing off)?"""
        if not is_feed(task) or task.prepared_at is None:
            return False
        st = self.kb.stations.get(task.prepare["machine"])
        return st is not None and st.fed_at >= task.prepared_at

    # -- finished feeds --------------------------------------------------------------
    def finished(self, task: M.Task) -> None:
        """A feed task succeeded: check the station took it, or send its prepare later."""
        if not is_feed(task):
            return
        if task.prepared_at is not None:
            feeds = dict(self.kb.get("feeds") or {})
            feeds[str(task.id)] = self.clock.now() + self.confirm
            self.kb.set("feeds", feeds)
        else:
            late = list(self.kb.get("late_prepares") or [])
            late.append(task.id)
            self.kb.set("late_prepares", late)

    def late(self) -> list[M.Task]:
        """Finished feeds whose PrepareMachine is still to be sent."""
        out = []
        for tid in self.kb.get("late_prepares") or []:
            t = self.kb.tasks.get(tid)
            if t is not None and t.state == M.DONE and t.prepared_at is None:
                out.append(t)
        return out

    def late_sent(self, task: M.Task) -> None:
        """The late PrepareMachine of ``task`` went out: verify the feed from now."""
        self.kb.set("late_prepares", [i for i in self.kb.get("late_prepares") or []
                                      if i != task.id])
        self.finished(task)

    def verify(self) -> list[M.Task]:
        """Feeds the station never took within ``confirm`` s; their products are
        repaired (:meth:`~teamserver.production.repair.Repairs.feed_lost`).  Returns those tasks."""
        feeds = dict(self.kb.get("feeds") or {})
        if not feeds:
            return []
        now = self.clock.now()
        lost = []
        for key, deadline in list(feeds.items()):
            t = self.kb.tasks.get(int(key))
            st = self.kb.stations.get(t.machine) if t is not None else None
            if t is None or st is None or t.prepared_at is None or st.fed_at >= t.prepared_at or self._counted(t):
                del feeds[key]
            elif now >= deadline:
                del feeds[key]
                if st.state not in ("BROKEN", "DOWN"):
                    log.warning("%s never took the workpiece of task %d (%s)", st.name, t.id,
                                t.kind)
                    self.repairs.feed_lost(t)
                    lost.append(t)
        self.kb.set("feeds", feeds)
        return lost

    def _counted(self, task: M.Task) -> bool:
        """A delivery the refbox counted for its order (whatever the station said)."""
        if task.kind != M.DELIVER:
            return False
        p = self.kb.products.get(task.product or "")
        o = self.kb.orders.get(p.order_id) if p is not None else None
        if o is None:
            return False
        ours = sum(1 for q in self.kb.products.values()
                   if q.order_id == o.id and q.state == "DELIVERED")
        return ours <= o.delivered

    # -- stations waiting for nothing ----------------------------------------------------
    def _due(self, task: M.Task) -> bool:
        """``task``'s workpiece exists: every step before it is done."""
        return all((d := self.kb.tasks.get(i)) is not None and d.state == M.DONE
                   for i in task.deps)

    def unstick(self) -> list[M.Product]:
        """Feed a spare base to each station PREPARED with an instruction no open task
        needs while one needs another instruction, or one whose workpiece exists needs
        another while those that need this one still wait for theirs (a product made
        again after its feed was lost: 2016 has neither a timeout of a PREPARED station
        nor a ResetMachine); returns the products made now.  Nothing under a stuck
        timeout (2025, see the module doc)."""
        if self.kb.profile.stuck_timeout is not None:
            return []
        flushing = dict(self.kb.get("flushing") or {})
        made = []
        wanted: dict[str, list[M.Task]] = {}
        for t in self.kb.open_tasks():
            if is_feed(t) or (t.prepare and "ss" in t.prepare):     # (a RETRIEVE too)
                wanted.setdefault(t.prepare["machine"], []).append(t)
        for machine, wants in wanted.items():
            instr = self.instruction(machine)
            if instr is None or self._owner(machine) is not None:
                continue
            same = [t for t in wants if t.prepare == instr]
            if same and (any(self._due(t) for t in same)
                         or not any(self._due(t) for t in wants if t.prepare != instr)):
                continue
            p = self.kb.products.get(flushing.get(machine, ""))
            if p is not None and p.state == "ACTIVE":
                continue
            p = self.cleanup.flush(machine, instr)
            if p is not None:
                flushing[machine] = p.id
                made.append(p)
                log.info("%s waits with %s that nothing needs: %s feeds it a spare base",
                         machine, instr, p.id)
        if made:
            self.kb.set("flushing", flushing)
        return made
