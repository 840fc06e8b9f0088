"""A short 2025 game over the in-process bus against a scripted team speaking the rcll2025
message set: reports in the first seconds of PRODUCTION, type feedback, the ground truth,
PrepareMachine rules, a C0 order produced and delivered by order id, ResetMachine."""
from __future__ import annotations

import pytest

from backends.sim.refbox import RefboxGame, Timing
from backends.sim.refbox.messages import enum_name, set_enum
from backends.sim.refbox.node import RefboxNode
from rll_bt import msgs
from rll_bt.clock import SimClock
from rll_bt.comm import Bus, MessageRegistry
from rll_bt.rules import profile

MS = msgs.message_set("rcll2025")
REG = MessageRegistry.from_message_set(MS)
KEYS = {"Caro": "cyan-secret", "Grips": "magenta-secret"}
SEED = 2                                     # order #1 is a C0 with a grey cap


@pytest.fixture
def match(bus_team):
    clock = SimClock()
    timing = Timing.from_profile(profile("rcll2025"), setup=3, exploration=20, production=120,
                                 overtime=0)
    game = RefboxGame("rcll2025", clock, seed=SEED, team_cyan="Caro", team_magenta="Grips",
                      timing=timing)
    bus = Bus(clock)
    node = RefboxNode.on_bus(game, bus, keys=KEYS)
    team = bus_team(bus, MS, KEYS["Caro"])
    other = bus_team(bus, MS, KEYS["Grips"], channel="magenta", team_name="Grips")
    ctrl = bus.stream_client("refbox", registry=REG, name="controller")

    def run(seconds, dt=0.1):
        for _ in range(int(round(seconds / dt))):
            clock.advance(dt)
            if abs(clock.now() % 1.0) < dt / 2:
                team.beacon(clock)
            node.step()
            team.poll()
            other.poll()

    def idle(machine, limit=30.0):
        """Run until the team's MachineInfo shows ``machine`` IDLE (not DOWN or busy)."""
        for _ in range(int(limit / 0.1)):
            mi = team.last("team", "MachineInfo")
            if mi is not None and machines(mi)[machine].state == "IDLE":
                return
            run(0.1)
        raise AssertionError(f"{machine} never IDLE")

    def ready(machine, limit=30.0):
        """Run until ``machine`` has its product at the output (a down period may delay it)."""
        for _ in range(int(limit / 0.1)):
            if game.stations[machine].state == "READY-AT-OUTPUT":
                return
            run(0.1)
        raise AssertionError(f"{machine} is {game.stations[machine].state}")
    run.ready, run.idle = ready, idle
    return clock, game, node, team, other, ctrl, run


def prepare(team, machine, clock=None, age=0.0, **instr):
    pm = MS.PrepareMachine()
    set_enum(pm, "team_color", "CYAN")
    pm.machine = machine
    if clock is not None:
        pm.sent_at = int(clock.epoch() - age)
    kind = machine[2:4].lower()
    sub = getattr(pm, f"instruction_{kind}")
    for k, v in instr.items():
        if isinstance(v, str) and k != "wp_description":
            set_enum(sub, k, v)
        else:
            setattr(sub, k, v)
    if not instr:
        sub.SetInParent()
    team.team.send(pm)


def machines(msg):
    return {m.name: m for m in msg.machines}


def lights(m):
    return {enum_name(ls, "color"): enum_name(ls, "state") for ls in m.lights}


def test_short_2025_game_over_the_bus(match):
    clock, game, node, team, other, ctrl, run = match
    world, lay = game.world, game.layout
    order = game.order(1)
    assert order.complexity == 0 and order.cap == "CAP_GREY"
    run(1.05)
    assert enum_name(team.last("public", "GameState"), "phase") == "PRE_GAME"
    start = MS.SetGameState()
    set_enum(start, "state", "RUNNING")
    ctrl.send(start)
    run(3.5)
    assert game.phase == "PRODUCTION" and game.exploring

    # exploring: every station of ours yellow, no zones; MachineReportInfo on the team channel
    mi = machines(team.last("team", "MachineInfo"))
    assert len(mi) == 7 and all(not m.HasField("zone") for m in mi.values())
    assert all(lights(m) == {"RED": "OFF", "YELLOW": "ON", "GREEN": "OFF"} for m in mi.values())
    assert team.last("team", "MachineReportInfo") is not None
    assert not team.got[("public", "ExplorationInfo")]

    # report all but C-CS2 by name, zone and rotation; C-CS2's zone by type only
    rep = MS.MachineReport()
    set_enum(rep, "team_color", "CYAN")
    for name in sorted(mi):
        e = rep.machines.add()
        if name == "C-CS2":
            e.type, e.zone = "CS", lay.zone(name)
        else:
            e.name, e.zone, e.rotation = name, lay.zone(name), lay.rotation(name)
    team.team.send(rep)
    run(1.5)
    mri = team.last("team", "MachineReportInfo")
    assert sorted(mri.reported_machines) == sorted(set(mi) - {"C-CS2"})
    assert [(f.type, f.name, enum_name(f, "team_color")) for f in mri.reported_types] == \
        [("CS", "C-CS2", "CYAN")]
    assert team.last("public", "GameState").points_cyan == 12
    mi = machines(team.last("team", "MachineInfo"))
    assert (mi["C-BS"].zone, mi["C-BS"].rotation) == (lay.zone("C-BS"), lay.rotation("C-BS"))
    assert not mi["C-CS2"].HasField("zone")

    # a report claiming magenta on the cyan channel is answered and ignored
    bad = MS.MachineReport()
    set_enum(bad, "team_color", "MAGENTA")
    e = bad.machines.add()
    e.name, e.zone, e.rotation = "M-BS", lay.zone("M-BS"), lay.rotation("M-BS")
    team.team.send(bad)
    run(0.5)
    assert "Invalid report for team MAGENTA of team CYAN" in \
        team.last("team", "AttentionMessage").message
    assert game.points("MAGENTA") == 0

    # PrepareMachine: refused for the unreported C-CS2, ignored when sent 10 s ago
    prepare(team, "C-CS2", operation="RETRIEVE_CAP")
    run(0.5)
    assert "C-CS2 is not yet correctly reported" in team.last("team", "AttentionMessage").message
    prepare(team, "C-BS", clock, age=10, side="OUTPUT", color=order.base)
    run(0.5)
    assert game.stations["C-BS"].state == "IDLE"

    # the exploration time passes: no more MachineReportInfo, every zone in MachineInfo
    run(20 - game.game_time + 0.2)
    assert not game.exploring and game.exploration.released
    n = len(team.got[("team", "MachineReportInfo")])
    run(3)
    assert len(team.got[("team", "MachineReportInfo")]) == n
    mi = machines(team.last("team", "MachineInfo"))
    assert mi["C-CS2"].zone == lay.zone("C-CS2") and mi["C-CS2"].correctly_reported
    assert lights(mi["C-CS2"]) == {"RED": "OFF", "YELLOW": "OFF", "GREEN": "ON"}
    oi = team.last("public", "OrderInfo")
    assert 1 in [o.id for o in oi.orders] and 11 not in [o.id for o in oi.orders]
    assert sum(o.competitive for o in oi.orders) <= 1

    # produce order #1 (C0): base from the BS, cap from CS1, deliver by order id
    prepare(team, "C-BS", clock, side="OUTPUT", color=order.base)
    run.ready("C-BS")
    base = world.take("C-BS", "output")
    run.idle("C-CS1")
    prepare(team, "C-CS1", clock, operation="RETRIEVE_CAP")
    run(0.5)
    world.put("C-CS1", "input", world.take("C-CS1", "shelf0"))
    run.ready("C-CS1")
    world.take("C-CS1", "output")                              # the cap-less carrier
    run.idle("C-CS1")
    prepare(team, "C-CS1", operation="MOUNT_CAP")
    run(0.5)
    world.put("C-CS1", "input", base)
    run.ready("C-CS1")
    product = world.take("C-CS1", "output")
    assert (product.base, product.rings, product.cap) == (order.base, (), "CAP_GREY")
    run.idle("C-DS")
    prepare(team, "C-DS", order_id=1)
    run(0.5)
    world.put("C-DS", "input", product)
    run(9)
    assert [e.data["how"] for e in game.events if e.kind == "delivery"] == ["in-time"]
    assert order.delivered["CYAN"] == 1
    run(2)
    assert team.last("public", "GameState").points_cyan == 12 + 2 + 20 + 10
    assert next(o for o in team.last("public", "OrderInfo").orders
                if o.id == 1).quantity_delivered_cyan == 1

    # ResetMachine over the wire; on the wrong channel it is refused
    reset = MS.ResetMachine()
    set_enum(reset, "team_color", "CYAN")
    reset.machine = "C-RS2"
    team.team.send(reset)
    run(0.3)
    assert machines(team.last("team", "MachineInfo"))["C-RS2"].state == "BROKEN"
    other.team.send(reset)
    run(0.3)
    assert "Invalid reset for team CYAN of team MAGENTA" in \
        other.last("team", "AttentionMessage").message

    # to the end: SETUP and PRODUCTION only, the final score on GameState
    run(80)
    assert game.phase == "POST_GAME"
    phases = {enum_name(g, "phase") for g in team.got[("public", "GameState")]}
    assert phases == {"PRE_GAME", "SETUP", "PRODUCTION", "POST_GAME"}
    gs = team.last("public", "GameState")
    assert gs.points_cyan == game.points("CYAN") == 44
    assert node.ignored["ResetMachine"] == 0
