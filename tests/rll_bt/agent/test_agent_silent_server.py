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
