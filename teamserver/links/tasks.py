"""The task link: what the dispatcher tells the robots and the refbox about tasks.

The dispatcher, the exploration and production decide during a tick; they
hand their word to a :class:`TaskLink` (a task for its robot, a cancel, a
PrepareMachine for the refbox) and never build or send a message
themselves.  The link queues what it is given and :meth:`TaskLink.flush`
sends it at the end of the tick, in the order it was decided, through the
team protocol (:class:`~teamserver.links.agents.AgentLink`) and the refbox
client (:class:`~teamserver.links.refbox.RefboxClient`).  A task protocol
other than ours (the league's AgentTask), acknowledgements or resending
under network faults belong here, not in the dispatcher.
"""
from __future__ import annotations

from collections.abc import Callable

from ..knowledge import model as M
from ..knowledge.kb import KnowledgeBase
from .agents import AgentLink
from .refbox import RefboxClient

TASK, CANCEL, PREPARE = "task", "cancel", "prepare"


class TaskLink:
    """See the module doc.  ``to_robot(robot, msg)`` sends to one robot;
    ``to_refbox(msg)`` sends on our team channel."""

    def __init__(self, kb: KnowledgeBase, codec: AgentLink, refbox: RefboxClient,
                 to_robot: Callable[[M.Robot | None, object], None],
                 to_refbox: Callable[[object], None]):
        self.kb = kb
        self.codec = codec
        self.refbox = refbox
        self.to_robot = to_robot
        self.to_refbox = to_refbox
        self.queue: list[tuple] = []     # (TASK, task), (CANCEL, task, reason, robot), (PREPARE, task)

    def send(self, task: M.Task) -> None:
        """Give ``task`` to its robot (``task.robot``)."""
        self.queue.append((TASK, task))

    def cancel(self, task: M.Task, reason: str) -> None:
        """Tell ``task``'s robot to stop it (the robot it has now: the dispatcher may
        put the task back in the pool before the queue is flushed)."""
        self.queue.append((CANCEL, task, reason, task.robot))

    def prepare(self, task: M.Task) -> None:
        """Send ``task``'s PrepareMachine (``task.prepare``) to the refbox."""
        self.queue.append((PREPARE, task))

    def flush(self) -> None:
        """Send what was queued, in order."""
        color = self.kb.get("team_color")
        for item in self.queue:
            kind, t = item[0], item[1]
            number = item[3] if kind == CANCEL else t.robot
            robot = self.kb.robots.get(number) if number is not None else None
            if kind == TASK:
                self.to_robot(robot, self.codec.task_msg(t, color))
            elif kind == CANCEL:
                self.to_robot(robot, self.codec.cancel_msg(t, item[2], number))
            elif kind == PREPARE:
                self.to_refbox(self.refbox.prepare_machine(t.prepare))
        self.queue.clear()
