"""The robots' task leases as the team server grants them (teamserver.links.leases): a lease
lengthened by the lag the robot reports, and no robot dropped (its task given away) before
every lease granted to it is surely over."""
import pytest

from teamserver.knowledge import model as M
from teamserver.links.leases import LAG_MAX, Leases
from tests.support.teamserver import Lockstep


def _leases(agent):
    return [(m.heard, m.lease) for m in agent.inbox if m.DESCRIPTOR.name == "Heartbeat" and m.HasField("lease")]


def _dropped_at(ls, numbers, seconds, dt=0.1):
    """Step ``seconds``; the clock time each of robots ``numbers`` was dropped at."""
    out = {}
    for _ in range(round(seconds / dt)):
        ls.step(dt=dt)
        for n in numbers:
            if n not in out and ls.server.kb.robots[n].status == M.LOST:
                out[n] = ls.clock.now()
    return out


def test_the_lease_is_the_drop_timeout_and_the_lag_the_robot_reports_and_the_robot_is_dropped_only_after_it():
    """Three robots fall silent at once after a status each: one without a lag (its lease the
    bare 10 s, as before), one with 4.5 s, one asking for more than the server grants."""
    ls = Lockstep()
    r1, r2, r3 = ls.agents
    for a in ls.agents:
        a.hello()
    ls.refbox.game_state("SETUP", "PAUSED")   # our colour: the server drops silent robots
    ls.step(n=2)
    r1.status(stamp=100.0)                    # each robot's own clock
    r2.status(stamp=50.0, lag=4.5)
    r3.status(stamp=7.0, lag=60.0)
    ls.step(dt=0.1)
    heard_at = ls.clock.now()                 # the statuses arrived in this step
    ls.step(dt=0.1, n=15)                     # a heartbeat to each (every second)
    assert _leases(r1)[-1] == (100.0, 10.0)
    assert _leases(r2)[-1] == (50.0, pytest.approx(14.5))
    assert _leases(r3)[-1] == (7.0, 10.0 + LAG_MAX)
    dropped = _dropped_at(ls, (1, 2, 3), 25.0)
    # the robot stops before heard + lease on its clock, which reads at least heard when its
    # status arrives: the server drops it only after heard_at + lease on its own
    assert heard_at + 10.0 < dropped[1] <= heard_at + 10.3
    assert heard_at + 14.5 < dropped[2] <= heard_at + 14.8
    assert heard_at + 10.0 + LAG_MAX < dropped[3] <= heard_at + 10.3 + LAG_MAX
    ls.close()


def test_a_restarted_server_takes_it_that_a_robot_may_hold_the_longest_lease(tmp_path):
    """The restarted server forgot the leases it granted: a robot that does not come back
    is dropped only once the longest lease it grants is over, counted from the restart."""
    ls = Lockstep(state=str(tmp_path / "ts.sqlite"))
    for a in ls.agents:
        a.hello()
    ls.refbox.game_state("SETUP", "PAUSED")
    ls.step(n=2)
    ls.agents[0].status(stamp=3.0, lag=2.0)
    ls.step(n=15)
    ls.restart()
    start = ls.clock.now()
    dropped = _dropped_at(ls, (1,), 25.0)
    assert start + 10.0 + LAG_MAX < dropped[1] <= start + 10.3 + LAG_MAX
    ls.close()


def test_the_leases_kept_as_granted():
    """What a server granted stays granted across a new connection of the robot (its stamps
    start afresh); a robot never granted a lease is judged by its silence alone."""
    leases = Leases(lag_max=5.0)
    assert leases.grant(1, 10.0) is None and leases.past(1, 0.0, 10.0, 10.1)
    leases.status(1, 200.0, 3.0, now=1.0)
    assert leases.grant(1, 10.0) == (200.0, 13.0) and leases.end(1) == 14.0
    leases.status(1, 199.0, None, now=2.0)    # an older stamp: nothing newer heard
    assert leases.grant(1, 10.0) == (200.0, 13.0)
    leases.reset(1)                           # a new connection
    assert leases.grant(1, 10.0) is None and leases.end(1) == 14.0
    leases.status(1, 5.0, 99.0, now=3.0)      # the lag at most lag_max
    assert leases.grant(1, 10.0) == (5.0, 15.0) and leases.end(1) == 18.0
    assert not leases.past(1, 3.0, 10.0, 17.9) and leases.past(1, 3.0, 10.0, 18.1)
    assert not leases.past(1, 10.0, 10.0, 19.0)           # heard since: not silent for 10 s
