"""The agent and the refbox: beacons on the team channel (bus and UDP),
standing still unless the game is RUNNING, machine reports."""
from __future__ import annotations

import time

import pytest

from rll_bt import msgs
from rll_bt.clock import SimClock
from rll_bt.comm import Bus, MessageRegistry, UdpPeer
from tests.support.agents import KEY, TEAM, TEAM_REG, TM, Rig, ScriptedServer

STATE = TM.RobotStatus.State


class BusRefbox:
    """A refbox on the bus: GameState on the public channel, ears on both team channels."""

    def __init__(self, bus: Bus, profile: str = "rcll2016"):
        self.ms = msgs.message_set(profile)
        self.reg = MessageRegistry.from_message_set(self.ms)
        self.public = bus.peer("public", registry=self.reg, name="refbox")
        self.cyan = bus.peer("cyan", registry=self.reg, key=KEY, name="refbox")
        self.magenta = bus.peer("magenta", registry=self.reg, key=KEY, name="refbox-m")
        self.eavesdropper = bus.peer("cyan", registry=self.reg, name="no key")
        self.got: list = []
        self.state, self.phase = "RUNNING", "PRODUCTION"

    def game_state(self) -> None:
        gs = self.ms.GameState(state=self.ms.GameState.State.Value(self.state),
                               phase=self.ms.GameState.Phase.Value(self.phase), team_cyan=TEAM, team_magenta="Other")
        gs.game_time.sec, gs.game_time.nsec = 10, 0
        self.public.send(gs)

    def pump(self) -> None:
        self.got += [rx.msg for rx in self.cyan.receive()]

    def of(self, name: str) -> list:
        return [m for m in self.got if m.DESCRIPTOR.name == name]


@pytest.fixture
def bus_rig():
    def make(profile="rcll2016", server_state="RUNNING", **kw):
        clock = SimClock()
        bus = Bus(clock)
        refbox = BusRefbox(bus, profile)
        srv = ScriptedServer(bus.stream_server("ts", registry=TEAM_REG, key=KEY), state=server_state, profile=profile)
        link = bus.stream_client("ts", registry=TEAM_REG, key=KEY)
        public = bus.peer("public", registry=refbox.reg, name="R1")
        rig = Rig(link, srv, clock, public=public,
                  team=lambda color: bus.peer(color.lower(), registry=refbox.reg, key=KEY, name="R1"),
                  profile=profile, **kw)
        ticker = {"next": 0.0}

        def refbox_round():
            if clock.now() >= ticker["next"]:           # GameState once a second, like the refbox
                ticker["next"] = clock.now() + 1.0
                refbox.game_state()
            refbox.pump()
        rig.extra.append(refbox_round)
        return rig, refbox, srv
    return make


def test_beacons_every_second_on_the_team_channel(bus_rig):
    rig, refbox, srv = bus_rig()
    rig.run(6.0)
    beacons = refbox.of("BeaconSignal")
    assert 5 <= len(beacons) <= 7
    b = beacons[-1]
    assert (b.number, b.team_name, b.peer_name) == (1, TEAM, "R1")
    assert b.team_color == refbox.ms.Team.Value("CYAN")              # learnt from GameState
    assert [x.seq for x in beacons] == list(range(1, len(beacons) + 1))
    assert abs(b.time.sec + b.time.nsec * 1e-9 - rig.clock.epoch()) < 1.5
    assert b.HasField("pose")
    assert refbox.eavesdropper.receive() == []                         # encrypted: nothing without the key
    assert refbox.magenta.receive() == []                              # never on the other team's channel


def test_the_stations_states_of_machine_info_reach_the_trees(bus_rig):
    """MachineInfo on the team channel: the agent keeps each station's state for its trees
    (the ``refbox_stations`` service a feed waits on)."""
    rig, refbox, srv = bus_rig()
    rig.run(2.0)
    mi = refbox.ms.MachineInfo(team_color=refbox.ms.Team.Value("CYAN"))
    for name, state in (("C-RS1", "PREPARED"), ("C-DS", "IDLE")):
        m = mi.machines.add()
        m.name, m.type, m.state = name, name[2:4], state
    refbox.cyan.send(mi)
    rig.run(0.5)
    view = rig.agent.services["refbox_stations"]
    assert view.heard and (view.state("C-RS1"), view.state("C-DS")) == ("PREPARED", "IDLE")
    assert view.state("C-CS1") is None


def test_beacon_pose_follows_the_robot(bus_rig):
    rig, refbox, srv = bus_rig(require_game=False)
    rig.agent.pose.start = None
    rig.backend.drive(0.5, 0.0, 0.0)
    rig.run(4.2)
    xs = [b.pose.x for b in refbox.of("BeaconSignal")]
    assert xs[0] < xs[-1] and xs[-1] == pytest.approx(0.5 * 4.0, abs=0.3)


def test_rcll2025_beacons_carry_the_task_and_the_finished_tasks(bus_rig):
    rig, refbox, srv = bus_rig(profile="rcll2025")
    rig.run(1.5)
    srv.task(31, "explore_zone", zone=23)
    rig.until(lambda: srv.results(31, "SUCCEEDED"), what="explore done")
    during = [b for b in refbox.of("BeaconSignal") if b.HasField("task")]
    assert during and during[0].task.task_id == 31                  # the AgentTask the robot got
    assert during[0].task.explore_machine.waypoint == "C_Z23" and not during[0].task.HasField("successful")
    rig.run(4.0)
    after = [b for b in refbox.of("BeaconSignal") if b.finished_tasks]
    assert len(after) >= 3 and all([(f.TaskId, f.successful) for f in b.finished_tasks] == [(31, True)]
                                   for b in after)                    # every beacon since lists it
    assert not refbox.of("BeaconSignal")[-1].HasField("task")


def test_beacons_over_udp_loopback():
    ms = msgs.message_set("rcll2016")
    reg = MessageRegistry.from_message_set(ms)
    clock = SimClock()
    agent_public = UdpPeer("127.0.0.1", 9, 0, registry=reg, channel="public")
    refbox_team = UdpPeer("127.0.0.1", 9, 0, registry=reg, channel="team", key=KEY)
    refbox_public = UdpPeer("127.0.0.1", agent_public.recv_port, 0, registry=reg, channel="public")
    made = []

    def team(color):
        peer = UdpPeer("127.0.0.1", refbox_team.recv_port, 0, registry=reg, channel="team", key=KEY)
        made.append((color, peer))
        return peer

    bus = Bus(clock)
    srv = ScriptedServer(bus.stream_server("ts", registry=TEAM_REG, key=KEY), color=1)
    rig = Rig(bus.stream_client("ts", registry=TEAM_REG, key=KEY), srv, clock, public=agent_public, team=team,
              real_wait=0.002)
    got = []
    try:
        gs = ms.GameState(state=2, phase=20, team_magenta=TEAM)
        gs.game_time.sec, gs.game_time.nsec = 1, 0
        deadline = time.monotonic() + 10.0
        while len(got) < 3 and time.monotonic() < deadline:
            refbox_public.send(gs)
            rig.run(0.5)
            got += [rx.msg for rx in refbox_team.receive()]
        assert [c for c, _p in made] == ["MAGENTA"]
        assert len(got) >= 3 and all(m.DESCRIPTOR.name == "BeaconSignal" for m in got)
        assert got[0].team_color == ms.Team.Value("MAGENTA") and got[0].number == 1
    finally:
        for p in (agent_public, refbox_team, refbox_public, *(p for _c, p in made)):
            p.close()


def test_stands_still_unless_running(bus_rig):
    rig, refbox, srv = bus_rig()
    refbox.state = "WAIT_START"
    rig.run(1.5)
    srv.task(41, "mount_cap", machine="C-CS1")
    rig.run(2.0)
    assert rig.drives() == [(0.0, "stop")] or all(m == "stop" for _t, m in rig.drives())   # never drove
    assert srv.running(41) and STATE.Name(srv.of("RobotStatus")[-1].state) == "STOPPED"
    refbox.state = "RUNNING"
    rig.until(lambda: rig.drives()[-1][1] == "drive", what="driving once RUNNING")
    ticks = rig.agent.run.ticks
    refbox.state = "PAUSED"
    t_pause = rig.clock.now()
    rig.run(3.0)
    while_paused = [(t, m) for t, m in rig.drives() if t > t_pause]
    assert while_paused and {m for _t, m in while_paused} == {"stop"}          # stopped, and stays put
    # at most the second until the refbox says PAUSED
    assert rig.agent.run.ticks - ticks <= 12
    assert STATE.Name(srv.of("RobotStatus")[-1].state) == "STOPPED"
    refbox.state = "RUNNING"
    rig.until(lambda: rig.drives()[-1][1] == "drive", what="driving again")
    drive_node = rig.agent.run.tree.root
    assert drive_node.starts == 2                                               # the tree started again
    assert STATE.Name(srv.of("RobotStatus")[-1].state) == "BUSY"
    refbox.phase = "POST_GAME"
    rig.until(lambda: rig.drives()[-1][1] == "stop", what="stopped in POST_GAME")
    assert not srv.results(41, "FAILED") and not srv.results(41, "CANCELLED")


def test_a_fresh_refbox_pause_outranks_the_team_server(bus_rig):
    rig, refbox, srv = bus_rig(server_state="RUNNING")
    refbox.state = "PAUSED"
    rig.run(1.5)
    srv.send_phase("RUNNING")
    rig.run(0.5)
    assert not rig.agent.gate.moving_allowed and rig.agent.gate.view.source == "refbox"
