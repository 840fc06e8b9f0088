"""The robot's lease on its task: how long it may keep working unheard.

The team server drops a robot it has not heard for its heartbeat timeout and
gives the robot's task to another robot (the same task, under the same id).
A robot cut off from the server cannot hear that happen, and a robot that
finished its task regardless would do it a second time beside the other
one.  So an rll-bt team server's heartbeats tell each robot its lease:
``heard``, the stamp (the robot's own clock) of the latest RobotStatus of
the robot the server heard, and ``lease``, the seconds of silence after
which it drops a robot.  The server cannot drop the robot before ``heard +
lease`` on the robot's clock (that status left the robot at ``heard`` and
reached the server no earlier); the robot stops its task ``margin`` s before,
reports it FAILED (``NOT_RUNNING``: the server tries the step again if it
still counts the task as the robot's), stops and waits.  A cut shorter than
the lease costs nothing: the robot finishes its task and reports when back.
A task that arrives while the lease has run out (back on the link, before
the server's next heartbeat) is not begun until a heartbeat renews it.
Without a lease from the server (a league team server) nothing is stopped.
"""
from __future__ import annotations

MARGIN = 0.5        # s before the end of the lease (a tick and the clocks' rates)


class TaskLease:
    """Follows the server's heartbeats (:meth:`heard`); :meth:`expired` at a clock time."""

    def __init__(self, margin: float = MARGIN):
        self.margin = margin
        self.until: float | None = None
        self.expiries = 0

    def heard(self, msg) -> None:
        """A message from the team server: a heartbeat with a lease extends it."""
        if msg.DESCRIPTOR.name != "Heartbeat" or not (msg.HasField("heard") and msg.HasField("lease")):
            return
        until = msg.heard + msg.lease - self.margin
        if self.until is None or until > self.until:
            self.until = until

    def expired(self, now: float) -> bool:
        return self.until is not None and now > self.until

    def tick(self, run, now: float, moving: bool = True):
        """Tick the task ``run`` (a :class:`~rll_bt.agent.runner.TaskRun`) if the lease
        lets it go on and the robot may ``move``; its outcome (FAILED when the lease ran
        out under it, also in a paused game: the task may be given away meanwhile), or None."""
        if not self.expired(now):
            return run.tick() if moving else None
        if run.ticks == 0:
            return None                 # not begun: wait for the server to say it hears us
        self.expiries += 1
        return run.abandon("NOT_RUNNING", self.why(now))

    def why(self, now: float) -> str:
        return (f"the team server has not confirmed hearing this robot for {now - self.until + self.margin:.1f} s "
                f"beyond its lease: it may give the task to another robot")
