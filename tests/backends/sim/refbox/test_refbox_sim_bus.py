"""The refbox on the in-process bus, against a scripted team speaking the wire protocol."""
from __future__ import annotations

import pytest

from backends.sim.refbox import RefboxGame, Timing
from backends.sim.refbox.messages import enum_name, set_enum
from backends.sim.refbox.node import Periodic, RefboxNode
from rll_bt import msgs
from rll_bt.clock import SimClock
from rll_bt.comm import Bus, MessageRegistry
from rll_bt.rules import profile

MS = msgs.message_set("rcll2016")
REG = MessageRegistry.from_message_set(MS)
KEYS = {"Caro": "cyan-secret", "Grips": "magenta-secret"}


@pytest.fixture
def setup(bus_team):
    def Team(bus, key=KEYS["Caro"], channel="cyan"):
        """A scripted robot of "Caro" (or, on "magenta", of "Grips") speaking the 2016 set."""
        return bus_team(bus, MS, key, channel)

    clock = SimClock()
    timing = Timing.from_profile(profile("rcll2016"), setup=3, exploration=20, production=120)
    game = RefboxGame("rcll2016", clock, seed=1, team_cyan="Caro", team_magenta="Grips",
                      timing=timing)
    bus = Bus(clock)
    node = RefboxNode.on_bus(game, bus, keys=KEYS)
    team = Team(bus)
    spy = Team(bus, key="not-the-key")
    other = Team(bus, key=KEYS["Grips"], channel="magenta")
    ctrl = bus.stream_client("refbox", registry=REG, name="controller")

    def run(seconds, dt=0.1, beacons=True):
        for _ in range(int(round(seconds / dt))):
            clock.advance(dt)
            if beacons and abs(clock.now() % 1.0) < dt / 2:
                team.beacon(clock)
            node.step()
            for t in (team, spy, other):
                t.poll()
    return clock, game, node, team, spy, other, ctrl, run


def test_full_exchange_with_a_scripted_team(setup):
    clock, game, node, team, spy, other, ctrl, run = setup
    run(2)
    gs = team.last("public", "GameState")
    assert enum_name(gs, "phase") == "PRE_GAME" and enum_name(gs, "state") == "WAIT_START"
    assert (gs.team_cyan, gs.team_magenta) == ("Caro", "Grips")
    beacon = team.last("public", "BeaconSignal")
    assert (beacon.team_name, beacon.peer_name, beacon.number) == ("LLSF", "RefBox", 0)
    assert len(team.got[("public", "VersionInfo")]) >= 4         # 0.5 s burst

    # control over public is refused, over the stream it starts the game
    start = MS.SetGameState()
    set_enum(start, "state", "RUNNING")
    team.public.send(start)
    run(1)
    assert game.state == "WAIT_START" and node.ignored["SetGameState"] == 1
    ctrl.send(start)
    run(4)
    assert game.phase == "EXPLORATION"

    # the robot is registered from its encrypted beacon
    ri = team.last("public", "RobotInfo")
    assert [(r.team, r.number, r.name, enum_name(r, "team_color")) for r in ri.robots] == \
        [("Caro", 2, "R2", "CYAN")]

    # exploration: read the type string for C-DS's lights off ExplorationInfo, report it
    ei = team.last("public", "ExplorationInfo")
    assert len(ei.signals) == 6 and len(ei.zones) == 24
    code = game.exploration.machine_lights("C-DS")
    type_string = next(s.type for s in ei.signals
                       if {enum_name(ls, "color"): enum_name(ls, "state") for ls in s.lights} == code)
    rep = MS.MachineReport()
    set_enum(rep, "team_color", "CYAN")
    e = rep.machines.add()
    e.name, e.type, e.zone = "C-DS", type_string, game.layout.machines["C-DS"].zone
    team.team.send(rep)
    run(1.5)
    assert team.last("team", "MachineReportInfo").reported_machines == ["C-DS"]
    assert team.last("public", "GameState").points_cyan == 8

    # a report claiming the other colour on the cyan channel is answered, not scored
    bad = MS.MachineReport()
    set_enum(bad, "team_color", "MAGENTA")
    team.team.send(bad)
    run(0.5)
    att = team.last("team", "AttentionMessage")
    assert att is not None and "Invalid report for team MAGENTA of team CYAN" in att.message

    # production: MachineInfo on the team channel, at once on a state change
    run(20)
    assert game.phase == "PRODUCTION"
    mi = team.last("team", "MachineInfo")
    assert enum_name(mi, "team_color") == "CYAN"
    assert sorted(m.name for m in mi.machines) == sorted(profile("rcll2016").machines("CYAN"))
    ds = next(m for m in mi.machines if m.name == "C-DS")
    assert ds.correctly_reported and ds.zone == game.layout.machines["C-DS"].zone
    assert enum_name(ds, "exploration_type_state") == "CORRECT_REPORT"
    assert len(team.last("team", "RingInfo").rings) == 4
    oi = team.last("public", "OrderInfo")
    assert [o.id for o in oi.orders] == [o.id for o in game.active_orders()]

    n_before = len(team.got[("team", "MachineInfo")])
    pm = MS.PrepareMachine()
    set_enum(pm, "team_color", "CYAN")
    pm.machine = "C-BS"
    set_enum(pm.instruction_bs, "side", "OUTPUT")
    set_enum(pm.instruction_bs, "color", "BASE_BLACK")
    team.team.send(pm)
    run(0.1)
    assert len(team.got[("team", "MachineInfo")]) > n_before
    bs = next(m for m in team.last("team", "MachineInfo").machines if m.name == "C-BS")
    assert bs.state == "PROCESSING"
    assert {enum_name(ls, "color"): enum_name(ls, "state") for ls in bs.lights} == \
        {"RED": "OFF", "YELLOW": "ON", "GREEN": "ON"}

    # the wrong key reads nothing of the cyan channel; magenta sees only its own machines
    assert not spy.got[("team", "MachineInfo")] and spy.team.stats.count("decrypt_failure") > 0
    assert spy.got[("public", "GameState")]             # the public channel is plain
    mi_m = other.last("team", "MachineInfo")
    assert {m.name[:2] for m in mi_m.machines} == {"M-"}

    # a PrepareMachine for cyan sent on the magenta channel is refused
    other.team.send(pm)
    run(0.5)
    assert "Invalid prepare" in other.last("team", "AttentionMessage").message


def test_gamestate_and_periods(setup):
    clock, game, node, team, spy, other, ctrl, run = setup
    game.start()
    run(10.05, beacons=False)
    counts = {k[1]: len(v) for k, v in team.got.items() if k[0] == "public"}
    assert 10 <= counts["GameState"] <= 11 and 10 <= counts["BeaconSignal"] <= 11
    assert 4 <= counts["RobotInfo"] <= 5                     # 2.5 s
    assert counts["ExplorationInfo"] >= 2                    # 1 s once EXPLORATION began at 3 s
    run(25, beacons=False)                                   # into PRODUCTION at 23 s
    oi = team.got[("public", "OrderInfo")]
    mi = team.got[("team", "MachineInfo")]
    # bursts: 10 OrderInfo 0.5 s apart, then 2 s; 30 MachineInfo 0.5 s apart
    assert 10 + 2 <= len(oi) <= 10 + 3 + 1
    assert 24 <= len(mi) <= 26


def test_periodic_schedule():
    p = Periodic(2.0, 0.5, 3)
    times = [t / 10 for t in range(0, 80) if p.due(t / 10)]
    assert times == [0.0, 0.5, 1.0, 3.0, 5.0, 7.0]
    once = Periodic(None, 0.5, 2)
    assert [t for t in (0, 0.5, 1.0, 5.0) if once.due(t)] == [0, 0.5]
    once.restart()
    assert once.due(9.0)


def test_garbage_and_unknown_messages_never_stop_the_node(setup):
    clock, game, node, team, spy, other, ctrl, run = setup
    game.start()
    team.team.send(MS.OrderInfo())                        # not for the refbox
    bad = MS.PrepareMachine()
    set_enum(bad, "team_color", "CYAN")
    bad.machine = "X"                                     # nonsense machine name
    team.team.send(bad)
    run(1)
    assert node.ignored["OrderInfo"] == 1
    assert game.state == "RUNNING"
