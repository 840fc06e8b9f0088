"""The task link: what the dispatcher tells the robots and the refbox about tasks.

The dispatcher, the exploration and production decide during a tick; they
hand their word to a :class:`TaskLink` (a task for its robot, a cancel, a
PrepareMachine for the refbox) and never build or send a message
themselves.  The link queues what it is given and :meth:`TaskLink.flush`
sends it at the end of the tick, in the order it was decided, through the
team protocol (:class:`~teamserver.links.agents.AgentLink`) and the refbox
client (:class:`~teamserver.links.refbox.RefboxClient`).  A task protocol
other than ours (the league's AgentTask) belongs here, not in the dispatcher.

Under network faults tasks and cancels are delivered reliably
(:mod:`rll_bt.comm.reliable`): kept per robot until the robot acknowledges
them, repeated meanwhile and at once when the robot comes back
(:meth:`TaskLink.welcome`); a task is no longer repeated once it is not
that robot's (cancelled, finished, given to another robot).  The robots'
final results are acknowledged (:meth:`TaskLink.incoming`) and acted on once.
"""
from __future__ import annotations

from collections.abc import Callable

from rll_bt.comm.reliable import Reliable

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
        self.reliable = Reliable(codec.clock)

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
        """Send what was queued, in order; then acknowledgements and what is due again."""
        color = self.kb.get("team_color")
        for item in self.queue:
            kind, t = item[0], item[1]
            number = item[3] if kind == CANCEL else t.robot
            robot = self.kb.robots.get(number) if number is not None else None
            if kind == TASK:
                self._deliver(robot, self.codec.task_msg(t, color))
            elif kind == CANCEL:
                self._deliver(robot, self.codec.cancel_msg(t, item[2], number))
            elif kind == PREPARE:
                self.to_refbox(self.refbox.prepare_machine(t.prepare))
        self.queue.clear()
        for number, ack in self.reliable.acks(lambda n: self.codec.ms.LinkAck(robot_id=n)):
            robot = self.kb.robots.get(number)
            if robot is not None:
                self.to_robot(robot, ack)
        for number, msg in self.reliable.due():
            robot = self.kb.robots.get(number)
            if robot is not None and robot.peer is not None and self._still_due(number, msg):
                self.to_robot(robot, msg)

    def _deliver(self, robot: M.Robot | None, msg) -> None:
        if robot is not None:
            # a cancel or a new copy of a task supersedes what was waiting for that task
            self.reliable.forget(robot.number, lambda m: int(m.task_id) != int(msg.task_id))
            self.reliable.track(robot.number, msg)
        self.to_robot(robot, msg)

    def _still_due(self, number: int, msg) -> bool:
        """Whether to repeat ``msg`` to robot ``number``: a task only while it is that robot's."""
        if msg.DESCRIPTOR.name != "Task":
            return True
        t = self.kb.tasks.get(int(msg.task_id))
        if t is not None and t.state == M.ASSIGNED and t.robot == number:
            return True
        self.reliable.forget(number, lambda m: m is not msg)
        return False

    def welcome(self, robot: M.Robot) -> None:
        """``robot`` (re)joined (on a new connection: what was on the old one is
        gone): everything unacknowledged, in the order it was decided (a cancel
        before the task that follows it), then its current task."""
        for msg in self.reliable.resend_now(robot.number):
            current = msg.DESCRIPTOR.name == "Task" and int(msg.task_id) == robot.task_id
            if not current and self._still_due(robot.number, msg):
                self.to_robot(robot, msg)
        t = self.kb.tasks.get(robot.task_id) if robot.task_id is not None else None
        if t is not None and t.state == M.ASSIGNED and t.robot == robot.number:
            self._deliver(robot, self.codec.task_msg(t, self.kb.get("team_color")))

    def incoming(self, msg) -> bool:
        """A message from a robot: whether to act on it (an acknowledgement, or the
        repeat of a result already acted on: no; acknowledgements owed are sent at
        the next :meth:`flush`)."""
        if msg.DESCRIPTOR.name == "LinkAck":
            self.reliable.on_ack(int(msg.robot_id), msg)
            return False
        if not hasattr(msg, "robot_id"):
            return True
        return self.reliable.received(int(msg.robot_id), msg)
