"""A robot that hears nothing from the team server finishes its task safely and
waits; its result reaches the server when the link is back, repeated until the
server acknowledges it."""
from rll_bt.agent.delivery import SERVER
from rll_bt.clock import SimClock
from rll_bt.comm import Bus
from rll_bt.comm.faults import FaultyTransport, LinkFaults
from rll_bt.comm.reliable import AT_CANCEL, AT_SUCCEEDED, AT_TASK
from tests.support.agents import KEY, TEAM_REG, TM, Rig, ScriptedServer


def _final(srv, tid):
    return srv.results(tid)


def test_a_robot_cut_off_mid_task_finishes_it_stops_waits_and_reports_when_back():
    clock = SimClock()
    bus = Bus(clock)
    srv = ScriptedServer(bus.stream_server("ts", registry=TEAM_REG, key=KEY))
    cut = (3.0, 13.0)
    link = FaultyTransport(bus.stream_client("ts", registry=TEAM_REG, key=KEY), LinkFaults(cuts=(cut,)),
                           clock=clock, stream=True)
    rig = Rig(link, srv, clock)
    rig.until(lambda: rig.agent.gate.moving_allowed, what="game running")
    rig.run(2.5 - clock.now())
    srv.task(4, "get_workpiece", machine="C-BS")
    rig.until(lambda: srv.running(4), what="task 4 running")
    assert clock.now() < cut[0]
    rig.until(lambda: rig.agent.run is None, seconds=9.0, what="task 4 done while cut off")
    assert cut[0] <= clock.now() < cut[1] and not _final(srv, 4)          # done, nobody heard it
    assert rig.drives()[-1][1] == "stop" and rig.agent.state() == "IDLE"  # the robot stopped and waits
    [result] = rig.agent.server.delivery.unacknowledged
    assert result.task_id == 4 and result.successful
    rig.run(cut[1] - clock.now() - 0.5)
    assert not rig.agent.connected and rig.agent.run is None and not _final(srv, 4)
    assert rig.drives()[-1][1] == "stop"                                   # still waiting, not moving

    rig.until(lambda: _final(srv, 4), seconds=3.0, what="the result after the cut")
    assert _final(srv, 4)[0].status == "SUCCEEDED" and _final(srv, 4)[0].code == "NONE"   # with its TaskOutcome
    rig.run(6.0)                                            # the scripted server does not acknowledge:
    assert len(_final(srv, 4)) >= 3                         # the result comes again and again
    ack = TM.LinkAck(robot_id=1)
    ack.items.add(comp_id=8000, msg_type=502, id=(4 << 3) | AT_SUCCEEDED)
    srv.send(ack)
    rig.run(1.0)
    n = len(_final(srv, 4))
    rig.run(20.0)
    assert len(_final(srv, 4)) == n and rig.agent.server.delivery.reliable.pending(SERVER) == []
    assert all(r.outcome is not None for r in _final(srv, 4))   # every copy after its TaskOutcome


def test_the_agent_acknowledges_tasks_and_cancels():
    clock = SimClock()
    bus = Bus(clock)
    srv = ScriptedServer(bus.stream_server("ts", registry=TEAM_REG, key=KEY))
    rig = Rig(bus.stream_client("ts", registry=TEAM_REG, key=KEY), srv, clock)
    rig.until(lambda: rig.agent.gate.moving_allowed, what="game running")
    srv.task(9, "get_workpiece", machine="C-BS")
    srv.cancel(9)
    rig.run(1.0)
    acked = {(i.msg_type, i.id) for m in srv.of("LinkAck") for i in m.items}
    assert {(502, (9 << 3) | AT_TASK), (502, (9 << 3) | AT_CANCEL)} <= acked


def test_a_robot_cut_off_longer_than_its_lease_stops_its_task_before_the_server_may_give_it_away():
    """The server drops a robot it has not heard for its heartbeat timeout and gives the robot's
    task to another: past that lease (its heartbeats say it) the robot stops the task, also when
    it stands in a paused game, and reports it FAILED when back; a task that arrives before the
    next heartbeat renews the lease waits for it."""
    clock = SimClock()
    bus = Bus(clock)
    srv = ScriptedServer(bus.stream_server("ts", registry=TEAM_REG, key=KEY))
    srv.lease = 3.0                     # the server drops a robot it has not heard for 3 s
    cut = (3.0, 20.0)
    link = FaultyTransport(bus.stream_client("ts", registry=TEAM_REG, key=KEY), LinkFaults(cuts=(cut,)),
                           clock=clock, stream=True)
    rig = Rig(link, srv, clock)
    lease = rig.agent.server.lease
    rig.until(lambda: rig.agent.gate.moving_allowed and lease.until is not None, what="a lease")
    rig.run(2.3 - clock.now())
    srv.task(4, "get_workpiece", machine="C-BS")
    rig.until(lambda: srv.running(4) and rig.agent.run.ticks > 0, what="task 4 running")
    srv.send_phase(state="PAUSED")          # the game is paused: the robot stands, on its task
    rig.until(lambda: not rig.agent.gate.moving_allowed, what="the pause")
    assert rig.agent.run is not None and not rig.agent.run.done and clock.now() < cut[0]
    rig.run(cut[0] - clock.now())
    heard = srv.heard                       # the last the server heard of the robot before the cut
    rig.until(lambda: rig.agent.run is None, seconds=10.0, what="task 4 stopped while cut off")
    stopped = clock.now()
    # stopped before the server could have dropped the robot (heard + lease), not long before
    assert cut[0] < stopped <= heard + srv.lease and stopped > heard + srv.lease - 1.5
    assert rig.drives()[-1][1] == "stop" and lease.expiries == 1
    [result] = rig.agent.server.delivery.unacknowledged
    assert result.task_id == 4 and not result.successful
    rig.run(cut[1] - clock.now() - 0.5)
    assert rig.drives()[-1][1] == "stop" and not _final(srv, 4)          # still waiting, not moving

    # back on the link: the result reaches the server; a task sent before the server's next
    # heartbeat (which renews the lease) waits for it, then begins
    rig.until(lambda: _final(srv, 4), seconds=3.0, what="the result after the cut")
    res = _final(srv, 4)[0]
    assert res.status == "FAILED" and res.code == "NOT_RUNNING" and "lease" in res.text
    srv.heartbeat_every = 10 ** 6
    srv.send_phase(state="RUNNING")
    srv.task(5, "get_workpiece", machine="C-BS")
    rig.until(lambda: rig.agent.run is not None, what="task 5 received")
    n = len(rig.drives())
    rig.run(2.0)
    assert rig.agent.run is not None and rig.agent.run.ticks == 0 and len(rig.drives()) == n   # not begun
    srv.send(TM.Heartbeat(robot_id=0, seq=1, heard=srv.heard, lease=srv.lease))
    rig.until(lambda: rig.agent.run is None or rig.agent.run.ticks > 0, what="task 5 begun")
    assert lease.expiries == 1


def test_a_cut_shorter_than_the_lease_costs_nothing():
    clock = SimClock()
    bus = Bus(clock)
    srv = ScriptedServer(bus.stream_server("ts", registry=TEAM_REG, key=KEY))
    srv.lease = 10.0
    link = FaultyTransport(bus.stream_client("ts", registry=TEAM_REG, key=KEY), LinkFaults(cuts=((3.0, 8.0),)),
                           clock=clock, stream=True)
    rig = Rig(link, srv, clock)
    rig.until(lambda: rig.agent.gate.moving_allowed and rig.agent.server.lease.until is not None, what="a lease")
    rig.run(2.5 - clock.now())
    srv.task(4, "get_workpiece", machine="C-BS")
    rig.until(lambda: _final(srv, 4), seconds=30.0, what="task 4 done")
    assert _final(srv, 4)[0].status == "SUCCEEDED" and rig.agent.server.lease.expiries == 0


def _lossy_rig(faults):
    """An agent whose link has ``faults`` and a scripted server granting leases as rll-bt's
    team server does (drop timeout 10 s); the agent is running a task that drives until
    halted (mount_cap) from 20 s on, its lag measured over those 20 s."""
    clock = SimClock()
    bus = Bus(clock)
    srv = ScriptedServer(bus.stream_server("ts", registry=TEAM_REG, key=KEY))
    srv.follow_leases(clock, timeout=10.0)
    link = FaultyTransport(bus.stream_client("ts", registry=TEAM_REG, key=KEY), faults, clock=clock,
                           stream=True, seed=1)
    rig = Rig(link, srv, clock)
    rig.until(lambda: rig.agent.gate.moving_allowed and rig.agent.server.lease.until is not None,
              seconds=20.0, what="a lease")
    rig.run(19.0 - clock.now())
    srv.task(4, "mount_cap", machine="C-CS1")
    rig.until(lambda: rig.agent.run is not None and rig.agent.run.ticks > 0, what="task 4 running")
    return clock, srv, rig


def test_a_stall_of_5_s_on_a_link_with_2_s_each_way_does_not_stop_the_task():
    """Issue 24, "lease slack": with 2 s of delay each way a confirmation is 4-5 s old when it
    reaches the robot, so a lease of the bare drop timeout (10 s) left 4.5 s of slack and a
    stall of that length (a chain of retransmissions, here both ways) stopped a task the
    server would have left the robot.  The robot reports that lag and the server lengthens the
    lease by it: a 5 s stall costs nothing, and the server never could give the task away."""
    stall = (25.0, 30.0)
    clock, srv, rig = _lossy_rig(LinkFaults(delay=2.0, jitter=0.2, stalls=(stall,)))
    lease = rig.agent.server.lease
    assert 3.5 < lease.lag < 7.0, lease.lag                     # 2 s up, 2 s down, up to 1 s to the heartbeat
    rig.run(stall[1] + 15.0 - clock.now())                      # the stall and 15 s after it
    assert lease.expiries == 0 and rig.agent.run is not None and not rig.agent.run.done
    assert srv.given_away is None
    assert max(s.stamp for s in srv.of("RobotStatus")) > stall[1]      # heard again after the stall
    assert min(lease for _heard, lease in srv.granted[-10:]) > 13.0      # 10 s and the lag


def test_a_real_silence_still_stops_the_task_before_the_server_may_give_it_away():
    """The same link cut for 40 s: the robot stops its task before the server could give it
    to another robot (silent 10 s and past every lease it granted), and not long before."""
    cut = (25.0, 65.0)
    clock, srv, rig = _lossy_rig(LinkFaults(delay=2.0, jitter=0.2, cuts=(cut,)))
    lease = rig.agent.server.lease
    rig.until(lambda: rig.agent.run is None, seconds=30.0, what="task 4 stopped while cut off")
    stopped = clock.now()
    assert lease.expiries == 1 and rig.drives()[-1][1] == "stop"
    rig.until(lambda: srv.given_away is not None, seconds=30.0, what="the server's drop")
    assert cut[0] < stopped < srv.given_away < cut[1]
    assert srv.given_away - stopped < 6.0          # the statuses it could not know had arrived, and the margin
    assert stopped - cut[0] > 10.0                 # a whole drop timeout of silence at least
    [result] = rig.agent.server.delivery.unacknowledged
    assert result.task_id == 4 and not result.successful
