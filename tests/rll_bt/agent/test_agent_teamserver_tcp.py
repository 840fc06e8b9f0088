"""An agent and a scripted team server over loopback TCP (a real, encrypted
StreamServer): register, task, running, result; cancellation; disconnect
and reconnect; restart, re-register and the machine map."""
from __future__ import annotations

import pytest

from rll_bt.agent import team_server_link
from rll_bt.clock import SimClock
from tests.support.agents import KEY, TEAM, TM, Rig, ScriptedServer, tcp_server

STATE = TM.RobotStatus.State


@pytest.fixture
def tcp():
    """(server transport, scripted server, clock, make_rig(key=KEY, **kw))."""
    made = []
    server_t = tcp_server()
    srv = ScriptedServer(server_t)
    clock = SimClock()

    def make_rig(key=KEY, port=None, **kw):
        link = team_server_link("127.0.0.1", port or server_t.port, key=key, clock=clock, backoff_initial=0.2,
                                backoff_max=1.0)
        rig = Rig(link, srv, clock, real_wait=0.002, **kw)
        made.append(rig)
        return rig

    yield server_t, srv, clock, make_rig
    for rig in made:
        rig.agent.link.close()
    srv.t.close()


def states(srv):
    return [STATE.Name(s.state) for s in srv.of("RobotStatus")]


def test_register_task_running_result(tcp):
    server_t, srv, clock, make_rig = tcp
    rig = make_rig()
    rig.until(lambda: srv.of("RobotHello"), what="RobotHello")
    hello = srv.of("RobotHello")[0]
    assert (hello.robot_id, hello.team_name, hello.peer_name, hello.restarted) == (1, TEAM, "R1", True)
    assert "grip" in hello.capabilities
    rig.until(lambda: rig.agent.gate.moving_allowed, what="GamePhase RUNNING")
    srv.task(5, "get_workpiece", machine="C-BS", side="OUTPUT")
    rig.until(lambda: srv.running(5), what="running")
    rig.until(lambda: srv.results(5, "SUCCEEDED"), what="SUCCEEDED")
    done = srv.results(5, "SUCCEEDED")[0]
    assert done.robot_id == 1 and done.code == "NONE" and done.task.successful and done.league_code is None
    busy = [s for s in srv.of("RobotStatus") if s.state == STATE.Value("BUSY")]
    assert busy and all(s.current_task_id == 5 for s in busy)
    assert states(srv)[-1] == "IDLE"
    drives = rig.drives()
    assert [m for _t, m in drives].count("drive") == 1 and drives[-1][1] == "stop"
    rig.run(2.0)
    seqs = [h.seq for h in srv.of("BeaconSignal")]
    assert len(seqs) >= 3 and seqs == sorted(seqs) and len(set(seqs)) == len(seqs)
    assert srv.of("RobotHello") == [hello]                # one registration on one connection


def test_an_agent_with_the_wrong_key_cannot_register(tcp):
    server_t, srv, clock, make_rig = tcp
    rig = make_rig(key="not-the-team-key")
    rig.run(3.0)
    assert srv.of("RobotHello") == [] and srv.got == []
    assert server_t.stats.total > 0                       # its frames arrived and were dropped


def test_cancel_stops_the_robot(tcp):
    server_t, srv, clock, make_rig = tcp
    rig = make_rig()
    rig.start_task(9, "mount_cap", machine="C-CS1")
    rig.until(lambda: rig.drives() and rig.drives()[-1][1] == "drive", what="driving")
    rig.run(1.0)
    t_cancel = clock.now()
    srv.cancel(9)
    rig.until(lambda: srv.results(9, "CANCELLED"), what="CANCELLED")
    res = srv.results(9, "CANCELLED")[0]
    assert res.code == "CANCELLED" and res.task.canceled and not res.task.successful
    after = [m for t, m in rig.drives() if t >= t_cancel]
    assert after and set(after) == {"stop"}               # stopped, and no drive since
    rig.run(1.0)
    assert rig.drives()[-1][1] == "stop" and states(srv)[-1] == "IDLE" and rig.agent.run is None
    srv.cancel(9)                                         # again: the same answer
    rig.until(lambda: len(srv.results(9, "CANCELLED")) == 2, what="second answer")
    srv.cancel(77)                                        # a task it never had
    rig.until(lambda: srv.results(77, "CANCELLED"), what="unknown task answered")


def test_disconnect_and_reconnect_keeps_the_task(tcp):
    server_t, srv, clock, make_rig = tcp
    rig = make_rig()
    rig.start_task(11, "get_workpiece", machine="C-BS")
    # the server drops the connection: the agent reconnects and says hello again, not restarted
    server_t.disconnect(srv.client)
    rig.until(lambda: len(srv.of("RobotHello")) == 2, what="second hello")
    assert srv.of("RobotHello")[1].restarted is False
    # the server goes away altogether while the task finishes
    server_t.close()
    rig.run(3.0)
    assert not rig.agent.connected and rig.agent.run is None          # done while nobody listened
    server2 = tcp_server(port=server_t.port)
    srv.t = server2
    rig.until(lambda: len(srv.of("RobotHello")) == 3, seconds=20.0, what="hello to the new server")
    rig.until(lambda: srv.results(11, "SUCCEEDED"), what="the result kept for the new server")
    assert srv.of("RobotHello")[2].restarted is False
    assert rig.agent.link.connections == 3 and rig.agent.registrations == 3


def test_restarted_agent_registers_again_and_gets_the_machine_map(tcp):
    server_t, srv, clock, make_rig = tcp
    first = make_rig()
    first.start_task(21, "mount_cap", machine="C-CS1")
    first.agent.link.close()                              # the agent process dies: no goodbye
    first.run(0.5)
    assert srv.client is None and not srv.results(21, "FAILED")

    class Machines:                                       # what the skills keep station poses in
        def __init__(self):
            self.poses = {}

        def set(self, name, pose):
            self.poses[name] = pose

        def subscribe(self, fn):
            pass

    class Skills:
        machines = Machines()

    second = make_rig(services={"skills": Skills()})
    second.until(lambda: "machine_map" in second.agent.services, what="machine map")
    hello = srv.of("RobotHello")[-1]
    assert hello.restarted is True and len(srv.of("RobotHello")) == 2
    known = second.agent.services["machine_map"]
    assert set(known) == {"C-CS1", "C-BS"} and known["C-BS"].pose.x == pytest.approx(5.0)
    assert set(Skills.machines.poses) == {"C-CS1", "C-BS"}
    assert second.agent.run is None                       # the old task died with the old process
