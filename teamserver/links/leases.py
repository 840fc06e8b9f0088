"""The robots' task leases, as the team server grants them (the robot's side: :mod:`rll_bt.agent.lease`).

A robot cut off from the server cannot hear that its task went to another
robot, so it may work unheard only as long as the server leaves it its
task.  Each heartbeat tells the robot ``heard``, the stamp (the robot's
clock) of the latest RobotStatus of it the server heard, and ``lease``: the
robot stops its task before ``heard + lease`` on its own clock.  The robot
learns of ``heard`` a round trip after it stamped that status (its way up,
the wait for the next heartbeat, the heartbeat's way down): on a radio with
2 s each way the confirmation it holds is 4-5 s old, and with a lease of
the bare drop timeout (10 s) a stall of 4-5 s stopped a task the server would
have left it.  So the robot measures that age (``RobotStatus.lease_lag``,
:class:`rll_bt.agent.lease.TaskLease`) and the server grants ``timeout +
lag`` (the lag at most ``lag_max``): the robot keeps about the drop timeout
of slack however slow its link.

The server keeps what it granted.  The status stamped ``heard`` reached it
at ``heard_at`` (its clock), so the robot's clock then read at least
``heard``, and at server time ``t`` at least ``heard + t - heard_at`` (the two
clocks run at one rate; the robot's half-second margin covers a drift): the
robot's lease from that heartbeat is surely over at ``heard_at + lease``.
:meth:`Leases.end` is the latest such time of every lease granted to a robot;
the server gives a robot's task away (drops it, or counts a cancel on it as
done) only once it has been silent for its drop timeout *and* that time has
passed (:meth:`Leases.past`).  A robot that never got a lease (a league
robot, or one that sent no stamped status yet) is judged by silence alone,
as before.  A restarted server does not know what it granted before: it
assumes the longest lease it grants, from its start (:meth:`Leases.restarted`).
"""
from __future__ import annotations

import math

#: the longest lag the server adds to a lease (s)
LAG_MAX = 10.0


class Leases:
    """Per robot number: the latest status stamp heard and when, the lag the robot
    reported, and the end (server clock) of every lease granted."""

    def __init__(self, lag_max: float = LAG_MAX):
        self.lag_max = lag_max
        self.heard: dict[int, float] = {}       # robot -> latest RobotStatus stamp heard (its clock)
        self.heard_at: dict[int, float] = {}    # robot -> when that status arrived (server clock)
        self.lag: dict[int, float] = {}         # robot -> the confirmation lag it reported (s)
        self.ends: dict[int, float] = {}        # robot -> when its leases are surely over (server clock)

    def status(self, number: int, stamp: float | None, lag: float | None, now: float) -> None:
        """A RobotStatus of robot ``number`` arrived at ``now``."""
        if stamp is not None and stamp > self.heard.get(number, -math.inf):
            self.heard[number], self.heard_at[number] = stamp, now
        if lag is not None and math.isfinite(lag):
            self.lag[number] = min(max(float(lag), 0.0), self.lag_max)

    def reset(self, number: int) -> None:
        """A new connection (perhaps a new process with a new clock): its stamps start
        afresh.  What was granted stays granted."""
        self.heard.pop(number, None)
        self.heard_at.pop(number, None)
        self.lag.pop(number, None)

    def grant(self, number: int, timeout: float) -> tuple[float, float] | None:
        """The (heard, lease) for a heartbeat to robot ``number`` now, recorded as
        granted; None: no stamped status heard on this connection."""
        if number not in self.heard:
            return None
        lease = timeout + self.lag.get(number, 0.0)
        end = self.heard_at[number] + lease
        self.ends[number] = max(end, self.ends.get(number, -math.inf))
        return self.heard[number], lease

    def end(self, number: int) -> float | None:
        """When every lease granted to robot ``number`` is surely over (None: none granted)."""
        return self.ends.get(number)

    def past(self, number: int, last_heard: float, timeout: float, now: float) -> bool:
        """Robot ``number``, last heard at ``last_heard``, may be given away at ``now``:
        silent for ``timeout`` and past every lease it was granted."""
        end = self.ends.get(number)
        return now - last_heard > timeout and (end is None or now > end)

    def restarted(self, number: int, timeout: float, now: float) -> None:
        """A server restarted at ``now`` that knew robot ``number``: it may have granted
        it the longest lease before it stopped."""
        self.ends[number] = max(now + timeout + self.lag_max, self.ends.get(number, -math.inf))
