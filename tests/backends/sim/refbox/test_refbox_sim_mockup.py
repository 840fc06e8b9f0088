"""Mockup mode: production without robots, a team playing by PrepareMachine alone."""
from __future__ import annotations

import pytest

from backends.sim.refbox import (
    BSInstruction,
    CSInstruction,
    DSInstruction,
    RefboxGame,
    RSInstruction,
    Timing,
    Workpiece,
)
from backends.sim.refbox.cli import mockup_wanted
from backends.sim.refbox.messages import set_enum
from backends.sim.refbox.node import RefboxNode
from rll_bt import msgs
from rll_bt.clock import SimClock
from rll_bt.comm import Bus
from rll_bt.rules import CYAN, profile

MS = msgs.message_set("rcll2016")
KEYS = {"Caro": "cyan-secret", "Grips": "magenta-secret"}


def rs_with(game, color, team="C"):
    return next(f"{team}-RS{k}" for k in "12" if color in game.rs_colors(f"{team}-RS{k}"))


def cs_with(game, cap, team="C"):
    return next(f"{team}-{k}" for k, c in game.config.cs_caps if c == cap)


def prepare_msg(machine, kind, **fields):
    pm = MS.PrepareMachine()
    set_enum(pm, "team_color", "CYAN")
    pm.machine = machine
    ins = getattr(pm, f"instruction_{kind}")
    for name, value in fields.items():
        if isinstance(value, str):
            set_enum(ins, name, value)
        else:
            setattr(ins, name, value)
    return pm


def test_prepare_only_team_completes_c1_over_the_bus(bus_team):
    clock = SimClock()
    timing = Timing.from_profile(profile("rcll2016"), setup=2, exploration=5, production=900,
                                 speed=4.0)
    game = RefboxGame("rcll2016", clock, seed=1, team_cyan="Caro", team_magenta="Grips",
                      timing=timing, mockup=True)
    bus = Bus(clock)
    node = RefboxNode.on_bus(game, bus, keys=KEYS)
    team = bus_team(bus, MS, KEYS["Caro"])
    order = next(o for o in game.orders if o.complexity == 1)
    ring, = order.rings
    rs, cs = rs_with(game, ring), cs_with(game, order.cap)
    cost = game.ring_costs[ring]

    def states():
        mi = team.last("team", "MachineInfo")
        return {m.name: m.state for m in mi.machines} if mi else {}

    # the script: what to prepare once the field shows a condition (at most once each)
    steps = [
        (lambda s: game.game_time >= order.begin - 40 and game.phase == "PRODUCTION",
         [prepare_msg("C-BS", "bs", side="OUTPUT", color=order.base),
          prepare_msg(rs, "rs", ring_color=ring),
          prepare_msg(cs, "cs", operation="RETRIEVE_CAP")]),
        (lambda s: s.get(cs) == "IDLE", [prepare_msg(cs, "cs", operation="MOUNT_CAP")]),
        (lambda s: s.get(cs) == "READY-AT-OUTPUT", [prepare_msg("C-DS", "ds", gate=order.gate)]),
    ]
    game.start()
    for _ in range(int((order.begin + 200) / 0.5)):
        clock.advance(0.5 / timing.speed)
        node.step()
        team.poll()
        if steps and game.phase == "PRODUCTION" and steps[0][0](states()):
            for pm in steps.pop(0)[1]:
                team.team.send(pm)
        if game.events and [e for e in game.events if e.kind == "delivery"]:
            break
    assert not steps
    delivery, = [e for e in game.events if e.kind == "delivery"]
    assert delivery.data["workpiece"] == Workpiece(order.base, (ring,), order.cap)
    assert delivery.data["how"] == "in-time" and delivery.data["order"] == order.id
    reasons = {e.reason: e.points for e in game.ledger.for_team(CYAN)
               if e.phase == "PRODUCTION"}
    s = game.profile.scoring
    assert reasons[f"mounted CC{cost} ring {ring} for order {order.id}"] == s.ring_by_cost[cost]
    assert reasons[f"mounted last ring for C1 order {order.id}"] == 10       # pre-cap (2016)
    assert reasons[f"mounted cap for order {order.id}"] == 10
    assert reasons[f"delivered item for order {order.id}"] == 20
    bases = [e for e in game.ledger.for_team(CYAN) if e.reason.startswith("added additional")]
    assert len(bases) == cost and all(e.points == 2 for e in bases)
    assert game.points(CYAN) == 20 + 10 + 10 + s.ring_by_cost[cost] + 2 * cost
    assert game.stations[rs].slide_loaded == 0
    assert not any(e.kind == "attention" and e.team == CYAN for e in game.events)


def test_wrong_instructions_still_break_stations(harness):
    h = harness(mockup=True).production()
    g = h.game
    wrong = next(c for c in g.ring_costs if c not in g.rs_colors("C-RS1"))
    assert g.prepare(CYAN, "C-RS1", RSInstruction(wrong), CYAN) == "broken"
    assert g.prepare(CYAN, "C-CS1", CSInstruction("MOUNT_CAP"), CYAN) == "broken"
    assert g.prepare(CYAN, "C-DS", DSInstruction(7), CYAN) == "broken"
    assert {h.station(m).state for m in ("C-RS1", "C-CS1", "C-DS")} == {"BROKEN"}
    assert not [e for e in h.awards(CYAN) if e.reason.startswith("added additional")]
    # a valid prepare whose workpiece is not fit waits for one, like a real station
    assert g.prepare(CYAN, "C-CS2", CSInstruction("RETRIEVE_CAP"), CYAN) == "prepared"
    h.run(42)        # carrier fed at 10, cap retrieved at 31.7, taken at 36.7, IDLE at 41.7
    assert g.prepare(CYAN, "C-CS2", CSInstruction("MOUNT_CAP"), CYAN) == "prepared"
    assert g.prepare(CYAN, "C-BS", BSInstruction("OUTPUT", "BASE_RED"), CYAN) == "prepared"
    h.run(46)        # base taken at 50.8, fed at 60.8, capped at 82.5, taken at 87.5
    color = g.rs_colors("C-RS2")[0]
    assert g.prepare(CYAN, "C-RS2", RSInstruction(color), CYAN) == "prepared"
    assert h.station("C-RS2").slide_loaded == g.ring_costs[color]
    h.run(10.25)     # the capped product is not fit for a ring: the RS keeps waiting
    assert h.station("C-RS2").state == "PREPARED"
    (wp, since), = g.mockup.held[CYAN].values()
    assert wp == Workpiece("BASE_RED", (), "CAP_BLACK") and since == pytest.approx(87.45)


def test_products_are_taken_and_a_broken_station_drops_its_workpiece(harness):
    h = harness(mockup=True).production()
    g = h.game
    assert g.prepare(CYAN, "C-BS", BSInstruction("INPUT", "BASE_SILVER"), CYAN) == "prepared"
    h.run(5.25)
    assert h.world.workpiece_at("C-BS", "input") == Workpiece("BASE_SILVER")
    h.run(5)
    assert h.world.workpiece_at("C-BS", "input") is None
    assert h.station("C-BS").state == "WAIT-IDLE"
    assert g.mockup.held[CYAN] == {"C-BS": (Workpiece("BASE_SILVER"), pytest.approx(7.638))}
    color = g.rs_colors("C-RS1")[0]
    assert g.prepare(CYAN, "C-RS1", RSInstruction(color), CYAN) == "prepared"
    assert g.mockup.held[CYAN] == {}            # on its way, arriving 10 s later
    g.reset_machine(CYAN, "C-RS1", CYAN)
    h.run(12)
    dropped = [e for e in h.events("workpiece") if e.data.get("what") == "dropped"]
    assert dropped and dropped[-1].machine == "C-RS1"
    assert h.station("C-RS1").state == "BROKEN"


def test_2025_retrieved_cap_and_delivery_by_order_id(harness25):
    h = harness25(exploration=0, mockup=True).production()
    g = h.game
    order = g.order(1)                        # standing: its window is open
    order.complexity, order.rings = 0, ()
    cs = cs_with(g, order.cap)
    assert g.prepare(CYAN, cs, CSInstruction("RETRIEVE_CAP"), CYAN) == "prepared"
    assert g.prepare(CYAN, "C-BS", BSInstruction("OUTPUT", order.base), CYAN) == "prepared"
    h.run(42)        # base taken at 8.8; carrier fed at 10, cap retrieved and discarded at 36.7
    assert g.prepare(CYAN, cs, CSInstruction("MOUNT_CAP"), CYAN) == "prepared"
    h.run(37)        # base fed at 52, capped at 73.7, taken at 78.7
    assert g.prepare(CYAN, "C-DS", DSInstruction(order_id=order.id), CYAN) == "prepared"
    h.run(20)        # fed at 89, within the 20 s of the prepare
    delivery, = h.events("delivery")
    assert delivery.data["workpiece"] == Workpiece(order.base, (), order.cap)
    assert delivery.data["how"] == "in-time"
    assert h.award_sum(CYAN) == 2 + 10 + g.profile.scoring.delivery_by_complexity[0]
    assert [e.data["what"] for e in h.events("workpiece") if e.data.get("mockup")] == \
        ["taken", "fed", "discarded", "carried", "fed", "taken", "carried", "fed"]


def test_mockup_off_leaves_stations_to_robots(harness):
    h = harness().production()
    g = h.game
    assert g.mockup is None
    g.prepare(CYAN, "C-BS", BSInstruction("OUTPUT", "BASE_RED"), CYAN)
    color = g.rs_colors("C-RS1")[0]
    g.prepare(CYAN, "C-RS1", RSInstruction(color), CYAN)
    h.run(60)
    assert h.station("C-BS").state == "READY-AT-OUTPUT"
    assert h.world.workpiece_at("C-BS", "output") == Workpiece("BASE_RED")
    assert h.station("C-RS1").state == "PREPARED" and h.station("C-RS1").slide_loaded == 0
    assert h.award_sum(CYAN, "PRODUCTION") == 0


def test_cli_auto_mockup_follows_the_worlds_robots():
    class WithRobots:
        robots = {("CYAN", 1): object()}
    assert mockup_wanted("auto", object()) and mockup_wanted("auto", type("W", (), {"robots": {}})())
    assert not mockup_wanted("auto", WithRobots())
    assert mockup_wanted("on", WithRobots()) and not mockup_wanted("off", object())
