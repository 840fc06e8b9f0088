"""The robot's lease on its task: how long it may keep working unheard.

The team server drops a robot it has not heard for its heartbeat timeout and
gives the robot's task to another robot (the same task, under the same id).
A robot cut off from the server cannot hear that happen, and a robot that
finished its task regardless would do it a second time beside the other
one.  So an rll-bt team server's heartbeats tell each robot its lease:
``heard``, the stamp (the robot's own clock) of the latest RobotStatus of
the robot the server heard, and ``lease``, the seconds after ``heard``
before which the server does not drop the robot (that status left the
robot at ``heard`` and reached the server no earlier: the server keeps
what it granted, :mod:`teamserver.links.leases`).  The robot stops its task
``margin`` s before ``heard + lease`` on its clock, reports it FAILED
(``NOT_RUNNING``: the server tries the step again if it still counts the
task as the robot's), stops and waits.  A cut shorter than the lease costs
nothing: the robot finishes its task and reports when back.  A task that
arrives while the lease has run out (back on the link, before the server's
next heartbeat) is not begun until a heartbeat renews it.  Without a lease
from the server (a league team server) nothing is stopped.

The robot hears of ``heard`` a round trip after it stamped that status (its
way up, the wait for the server's next heartbeat, the heartbeat's way
down): 4-5 s on a radio with 2 s of delay each way.  With a lease of the bare
drop timeout (10 s) it kept only about 4.5 s of slack, and a stall of that
length (a chain of retransmissions) stopped a task the server would have
left it.  So the robot measures that age, ``now - heard`` whenever a
heartbeat confirms a newer status (a smoothed mean plus twice the smoothed
deviation, as TCP estimates a round trip), and reports it in every
RobotStatus (``lease_lag``); the server lengthens the lease it grants by it
(by at most 10 s) and gives the task away only once the
lease is surely over.  So the robot keeps about the drop timeout of slack
on any link, and a real silence still stops it before the server may
reassign its task.
"""
from __future__ import annotations

MARGIN = 0.5        # s before the end of the lease (a tick and the clocks' rates)
GAIN, DEV_GAIN = 1 / 8, 1 / 4       # the lag's smoothing (TCP's round-trip estimator)


class TaskLease:
    """Follows the server's heartbeats (:meth:`heard`); :meth:`expired` at a clock time;
    :attr:`lag` to report (None: not measured yet)."""

    def __init__(self, margin: float = MARGIN):
        self.margin = margin
        self.until: float | None = None
        self.expiries = 0
        self.confirmed: float | None = None     # the newest status stamp a heartbeat confirmed
        self.mean: float | None = None          # smoothed age of a confirmation when it arrives
        self.dev = 0.0                          # ... and its smoothed deviation

    def heard(self, msg, now: float | None = None) -> None:
        """A message from the team server (at clock time ``now``): a heartbeat with a
        lease extends it; one that confirms a newer status is a sample of the lag."""
        if msg.DESCRIPTOR.name != "Heartbeat" or not (msg.HasField("heard") and msg.HasField("lease")):
            return
        until = msg.heard + msg.lease - self.margin
        if self.until is None or until > self.until:
            self.until = until
        if now is not None and (self.confirmed is None or msg.heard > self.confirmed):
            self.confirmed = msg.heard
            self.sample(max(0.0, now - msg.heard))

    def sample(self, age: float) -> None:
        """A confirmation ``age`` s old arrived."""
        if self.mean is None:
            self.mean, self.dev = age, age / 4
        else:
            self.dev += DEV_GAIN * (abs(age - self.mean) - self.dev)
            self.mean += GAIN * (age - self.mean)

    @property
    def lag(self) -> float | None:
        """The lag the robot asks the server to add to its lease (s)."""
        return None if self.mean is None else self.mean + 2 * self.dev

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
