"""The task link: what the dispatcher tells the robots and the refbox about tasks.

The dispatcher, the exploration and production decide during a tick; they
hand their word to a :class:`TaskLink` (a task for its robot, a cancel, a
PrepareMachine for the refbox) and never build or send a message
themselves.  The link queues what it is given and :meth:`TaskLink.flush`
sends it at the end of the tick, in the order it was decided, as the
league's AgentTask (:class:`~teamserver.links.agents.AgentLink`, with
rll-bt's TaskDetail for robots that speak rll-bt) and through the refbox
client (:class:`~teamserver.links.refbox.RefboxClient`).

Under network faults tasks and cancels to a robot that speaks rll-bt are
delivered reliably (:mod:`rll_bt.comm.reliable`): kept per robot until the
robot acknowledges them (``LinkAck``), repeated meanwhile (a task with its
TaskDetail) and at once when the robot comes back (:meth:`TaskLink.welcome`);
a task is no longer repeated once it is not that robot's (cancelled,
finished, given to another robot).  The robots' final results are
acknowledged (:meth:`TaskLink.incoming`) and acted on once.  A robot of the
league knows no ``LinkAck``: it gets each task once, and again when it
comes back; its beacons say what it finished.

A task taken back from a robot (cancelled, and put back in the pool) may
still run on it: the cancel can be lost in a cut, and the robot goes on
until its lease runs out (:mod:`rll_bt.agent.lease`).  So the link keeps
each cancel's *stop owed* (:meth:`TaskLink.stop_owed`) until the robot has
provably stopped: it acknowledged the cancel (an rll-bt agent stops the task
before it acknowledges), sent a final result of that assignment, or (a
league robot, which knows no ``LinkAck``) its beacon says it runs something
else or nothing (:meth:`TaskLink.runs`), and no robot's latest status says
it runs the task (:meth:`TaskLink.said_running`: this also holds after a
restart of the server, which forgets the stops owed); the
dispatcher gives the task to nobody meanwhile unless the robot has been
silent past its lease (:mod:`teamserver.dispatch.readiness`).
"""
from __future__ import annotations

from collections.abc import Callable

from rll_bt.comm.reliable import AT_SUCCEEDED, AT_TASK, Reliable, agent_task_what

from ..knowledge import model as M
from ..knowledge.kb import KnowledgeBase
from .agents import AgentLink, from_wire, wire_id
from .refbox import RefboxClient

TASK, CANCEL, PREPARE = "task", "cancel", "prepare"
MAX_STOPS = 256         # stops owed remembered (the oldest is given up)


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
        self.queue: list[tuple] = []     # (TASK, task), (CANCEL, task, reason, robot, wire), (PREPARE, task)
        self.reliable = Reliable(codec.clock)
        self._before: dict[tuple, list] = {}     # (robot, link key) -> the TaskDetail that goes before that task
        # task id -> (robot, wire id, the cancel's link key): cancelled on a robot not yet known to have stopped
        self._stops: dict[int, tuple[int, int, tuple | None]] = {}

    def send(self, task: M.Task) -> None:
        """Give ``task`` to its robot (``task.robot``)."""
        self.queue.append((TASK, task))

    def cancel(self, task: M.Task, reason: str) -> None:
        """Tell ``task``'s robot to stop it (the robot and assignment it has now: the
        dispatcher may put the task back in the pool before the queue is flushed)."""
        self.queue.append((CANCEL, task, reason, task.robot, wire_id(task)))
        if task.robot is not None:          # owed from now: the dispatcher may reassign in this tick
            self._owe_stop(task, task.robot, wire_id(task), None)

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
                self._deliver(robot, self.codec.task_msgs(t, color, robot))
            elif kind == CANCEL:
                msg = self.codec.cancel_wire(item[4], int(number or 0), color)
                if number is not None and self._stops.get(t.id, (None, None))[:2] == (int(number), int(item[4])):
                    self._stops[t.id] = (int(number), int(item[4]), self.reliable.key(msg))
                self._deliver(robot, [msg])
            elif kind == PREPARE:
                self.to_refbox(self.refbox.prepare_machine(t.prepare))
        self.queue.clear()
        for number, ack in self.reliable.acks(lambda n: self.codec.ms.LinkAck(robot_id=n)):
            robot = self.kb.robots.get(number)
            if robot is not None and self.codec.speaks_rllbt(robot):     # a league robot knows no LinkAck
                self.to_robot(robot, ack)
        for number, msg in self.reliable.due():
            robot = self.kb.robots.get(number)
            if robot is not None and robot.peer is not None and self._still_due(number, msg):
                self._repeat(robot, msg)
        self._prune()

    # -- stops owed ---------------------------------------------------------------------------
    def _owe_stop(self, task: M.Task, number: int, wire: int, key) -> None:
        self._stops.pop(task.id, None)
        self._stops[task.id] = (int(number), int(wire), key)
        while len(self._stops) > MAX_STOPS:
            self._stops.pop(next(iter(self._stops)))

    def stop_owed(self, task_id: int) -> int | None:
        """The robot that may still run task ``task_id`` after it was cancelled on it
        (the cancel neither acknowledged nor answered with a result yet), or None."""
        s = self._stops.get(int(task_id))
        return s[0] if s is not None else None

    def stops_owed(self) -> dict[int, int]:
        """Every task cancelled on a robot not yet known to have stopped it: task id -> robot."""
        return {tid: s[0] for tid, s in self._stops.items()}

    def said_running(self, task_id: int) -> int | None:
        """A robot whose latest RobotStatus says it runs an assignment of task
        ``task_id`` (also after a restart of the server, which forgot its stops owed), or None."""
        return next((n for n, wire in self.codec.running.items() if from_wire(wire)[0] == int(task_id)), None)

    def past_lease(self, robot: M.Robot, timeout: float, now: float) -> bool:
        """``robot`` may be given away: silent for ``timeout`` and past every lease
        granted to it (:meth:`teamserver.links.leases.Leases.past`)."""
        return self.codec.leases.past(robot.number, robot.last_heartbeat, timeout, now)

    def stopped(self, number: int, task_id: int | None = None) -> None:
        """Robot ``number`` has stopped task ``task_id`` (None: every task; it was
        dropped, past its lease)."""
        for tid in [tid for tid, s in self._stops.items()
                    if s[0] == int(number) and (task_id is None or tid == int(task_id))]:
            del self._stops[tid]

    def runs(self, number: int, wire: int | None) -> None:
        """Robot ``number`` says (a league robot's beacon) it runs assignment ``wire``
        (None: nothing): it has stopped the others cancelled on it."""
        for tid in [tid for tid, s in self._stops.items() if s[0] == int(number) and s[1] != wire]:
            del self._stops[tid]

    def _stop_heard(self, msg) -> None:
        """A LinkAck or a final result from a robot: the stops it proves."""
        if not self._stops or not hasattr(msg, "robot_id"):
            return
        number = int(msg.robot_id)
        if msg.DESCRIPTOR.name == "LinkAck":
            acked = {(int(i.comp_id), int(i.msg_type), int(i.id)) for i in msg.items}
            done = [tid for tid, s in self._stops.items() if s[0] == number and s[2] in acked]
        elif msg.DESCRIPTOR.name == "AgentTask" and agent_task_what(msg) >= AT_SUCCEEDED:
            done = [tid for tid, s in self._stops.items() if s[0] == number and s[1] == int(msg.task_id)]
        else:
            return
        for tid in done:
            del self._stops[tid]

    def _deliver(self, robot: M.Robot | None, msgs: list) -> None:
        """Send ``msgs`` (an AgentTask last, what goes with it before), and keep the
        AgentTask until an rll-bt robot acknowledges it."""
        msg = msgs[-1]
        if robot is not None and self.codec.speaks_rllbt(robot):
            # a cancel or a new copy of a task supersedes what was waiting for that task
            wire = int(msg.task_id)
            self.reliable.forget(robot.number, lambda m: int(m.task_id) != wire)
            if self.reliable.track(robot.number, msg) and len(msgs) > 1:
                self._before[(robot.number, self.reliable.key(msg))] = msgs[:-1]
        for m in msgs:
            self.to_robot(robot, m)

    def _repeat(self, robot: M.Robot, msg) -> None:
        """A copy of ``msg`` that was not acknowledged, after what goes with it."""
        for m in self._before.get((robot.number, self.reliable.key(msg)), ()):
            self.to_robot(robot, m)
        self.to_robot(robot, msg)

    def _prune(self) -> None:
        if len(self._before) > 32 and len(self._before) > len(self.reliable.pending()):
            live = {(n, self.reliable.key(m)) for n in list(self.kb.robots) for m in self.reliable.pending(n)}
            for k in [k for k in self._before if k not in live]:
                del self._before[k]

    def _still_due(self, number: int, msg) -> bool:
        """Whether to repeat ``msg`` to robot ``number``: a task only while it is that robot's."""
        if agent_task_what(msg) != AT_TASK:
            return True
        t = self.codec.task_of(int(msg.task_id))
        if t is not None and t.state == M.ASSIGNED and t.robot == number:
            return True
        self.reliable.forget(number, lambda m: m is not msg)
        return False

    def welcome(self, robot: M.Robot) -> None:
        """``robot`` (re)joined (on a new connection: what was on the old one is
        gone): everything unacknowledged, in the order it was decided (a cancel
        before the task that follows it), then its current task."""
        t = self.kb.tasks.get(robot.task_id) if robot.task_id is not None else None
        if t is None or t.state != M.ASSIGNED or t.robot != robot.number:
            t = None
        if self.codec.speaks_rllbt(robot):
            for msg in self.reliable.resend_now(robot.number):
                current = t is not None and agent_task_what(msg) == AT_TASK and int(msg.task_id) == wire_id(t)
                if not current and self._still_due(robot.number, msg):
                    self._repeat(robot, msg)
        if t is not None:
            self._deliver(robot, self.codec.task_msgs(t, self.kb.get("team_color"), robot))

    def incoming(self, msg) -> bool:
        """A message from a robot: whether to act on it (an acknowledgement, or the
        repeat of a result already acted on: no; acknowledgements owed are sent at
        the next :meth:`flush`)."""
        self._stop_heard(msg)
        if msg.DESCRIPTOR.name == "LinkAck":
            self.reliable.on_ack(int(msg.robot_id), msg)
            return False
        if not hasattr(msg, "robot_id"):
            return True
        return self.reliable.received(int(msg.robot_id), msg)
