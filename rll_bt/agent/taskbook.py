"""What a robot knows of its tasks, by task id.

A team server may send a task again (it reconnected, it restarted, a
message may have crossed its result): the book makes sure a task id is run
at most once.  Every id the robot took is in exactly one place:

- ``current``: the task it runs;
- ``waiting``: tasks that arrived while it was busy (the league's robots
  queue them; rll-bt's team server sends a task early only to run after the
  current one, TaskDetail ``after``: it starts once that one succeeded and is
  refused otherwise, :meth:`TaskBook.may_follow`);
- ``finished``: the last :attr:`keep` results, each the league's result (the
  AgentTask echoed with ``successful`` / ``canceled`` / ``error_code``) and
  rll-bt's ``TaskOutcome``.

Results go out when the task ends (delivered reliably to an rll-bt team
server, :mod:`rll_bt.agent.delivery`) and again whenever the server sends the
task once more, except a task the server cancelled and gives out again
later under the same id (:meth:`TaskBook.given_again`, by the TaskDetail's
``issued_at``): that one runs again.
"""
from __future__ import annotations

from collections import OrderedDict, deque
from dataclasses import dataclass
from typing import Any

KEEP = 1024     # results remembered to answer re-sent tasks and cancels


@dataclass
class Entry:
    """A task the robot took: the AgentTask as received, rll-bt's TaskDetail
    (or None), the tree kind and parameters it runs with, paused or not."""
    task: Any
    detail: Any
    kind: str
    params: dict
    paused: bool = False

    @property
    def task_id(self) -> int:
        return int(self.task.task_id)

    @property
    def after(self) -> int | None:
        """The task (id) this one was sent to run after (rll-bt's TaskDetail ``after``), or None."""
        d = self.detail
        return int(d.after) if d is not None and d.HasField("after") else None


@dataclass
class Result:
    """A finished task's result: the league's message and rll-bt's outcome."""
    task: Any                   # AgentTask with successful / canceled / error_code
    outcome: Any                # rllbt.TaskOutcome

    @property
    def successful(self) -> bool:
        return bool(self.task.successful)


class TaskBook:
    def __init__(self, keep: int = KEEP):
        self.keep = keep
        self.current: Entry | None = None
        self.waiting: deque[Entry] = deque()
        self.finished: OrderedDict[int, Result] = OrderedDict()
        self.issued: dict[int, float] = {}      # task id -> TaskDetail.issued_at of the copy the robot took

    def where(self, task_id: int) -> str | None:
        """"current", "waiting", "finished" or None: where ``task_id`` is."""
        tid = int(task_id)
        if self.current is not None and self.current.task_id == tid:
            return "current"
        if any(e.task_id == tid for e in self.waiting):
            return "waiting"
        if tid in self.finished:
            return "finished"
        return None

    def entry(self, task_id: int) -> Entry | None:
        """The current or waiting entry of ``task_id``."""
        tid = int(task_id)
        if self.current is not None and self.current.task_id == tid:
            return self.current
        return next((e for e in self.waiting if e.task_id == tid), None)

    def take(self, entry: Entry) -> bool:
        """A new task: it becomes the current one if there is none (True), else it waits (False)."""
        if entry.detail is not None and entry.detail.HasField("issued_at"):
            self.issued[entry.task_id] = float(entry.detail.issued_at)
        if self.current is None:
            self.current = entry
            return True
        self.waiting.append(entry)
        return False

    def drop_waiting(self, task_id: int) -> Entry | None:
        """Take a waiting task out of the queue (it was cancelled)."""
        e = next((e for e in self.waiting if e.task_id == int(task_id)), None)
        if e is not None:
            self.waiting.remove(e)
        return e

    def next(self) -> Entry | None:
        """With no current task, the first waiting one becomes current."""
        if self.current is None and self.waiting:
            self.current = self.waiting.popleft()
        return self.current

    def finish(self, task_id: int, result: Result) -> None:
        """``task_id`` ended (or was refused) with ``result``."""
        tid = int(task_id)
        if self.current is not None and self.current.task_id == tid:
            self.current = None
        self.finished[tid] = result
        self.finished.move_to_end(tid)
        while len(self.finished) > self.keep:
            self.issued.pop(self.finished.popitem(last=False)[0], None)

    def may_follow(self, entry: Entry) -> bool | None:
        """May ``entry`` start as far as the task it was sent to run after goes?  True once
        that one succeeded (or without one), False if it ended otherwise or is unknown
        here, None while it still runs or waits."""
        if entry.after is None:
            return True
        if self.where(entry.after) in ("current", "waiting"):
            return None
        r = self.finished.get(entry.after)
        return r is not None and r.successful

    def result(self, task_id: int) -> Result | None:
        return self.finished.get(int(task_id))

    def given_again(self, task_id: int, detail) -> bool:
        """A copy of finished task ``task_id`` (its TaskDetail ``detail``) gives out
        again a task the server cancelled on this robot: issued after the copy
        the robot ran (a late copy of the cancelled task is not)."""
        r = self.finished.get(int(task_id))
        if r is None or not r.task.canceled or detail is None or not detail.HasField("issued_at"):
            return False
        return float(detail.issued_at) > self.issued.get(int(task_id), float("inf"))

    def forget(self, task_id: int) -> None:
        """Forget the result of ``task_id`` (it is given out again)."""
        self.finished.pop(int(task_id), None)
        self.issued.pop(int(task_id), None)

    def beacon_tasks(self, n: int) -> tuple:
        """What a beacon carries: the AgentTask the robot runs now (field 9, or None) and the last
        ``n`` finished tasks with whether each succeeded (field 10)."""
        current = self.current.task if self.current is not None else None
        return current, ([(tid, r.successful) for tid, r in list(self.finished.items())[-n:]] if n else [])
