"""Production: PrepareMachine rules, station state machines and lights, workpieces,
and every production scoring rule of the 2016 fact sheet."""
from __future__ import annotations

import pytest

from backends.sim.refbox import BSInstruction, CSInstruction, DSInstruction, RSInstruction, Workpiece
from rll_bt.rules import CYAN, MAGENTA, MPS_TIMES

T = MPS_TIMES        # the real machines' times

GREEN = {"RED": "OFF", "YELLOW": "OFF", "GREEN": "ON"}
GREEN_BLINK = {"RED": "OFF", "YELLOW": "OFF", "GREEN": "BLINK"}
BUSY = {"RED": "OFF", "YELLOW": "ON", "GREEN": "ON"}
READY = {"RED": "OFF", "YELLOW": "ON", "GREEN": "OFF"}
WAIT_IDLE = {"RED": "OFF", "YELLOW": "BLINK", "GREEN": "OFF"}
BROKEN = {"RED": "BLINK", "YELLOW": "BLINK", "GREEN": "OFF"}
DOWN = {"RED": "ON", "YELLOW": "OFF", "GREEN": "OFF"}


def rs_color(game, rs, cost=None):
    """A ring colour of ``rs`` (with the given cost if asked)."""
    return next(c for c in game.rs_colors(rs) if cost is None or game.ring_costs[c] == cost)


def states(h, machine):
    return [e.data["state"] for e in h.events("machine") if e.machine == machine]


def deliver(h, wp, gate, team=CYAN):
    """Run one DS cycle; returns (points awarded by it, the delivery event)."""
    ds = f"{'C' if team == CYAN else 'M'}-DS"
    n = len(h.game.ledger.entries)
    assert h.game.prepare(team, ds, DSInstruction(gate), team) == "prepared"
    h.world.put(ds, "input", wp)
    h.run(5.0)
    assert h.station(ds).state == "IDLE" and h.world.workpiece_at(ds, "input") is None
    return (sum(e.points for e in h.game.ledger.entries[n:]), h.events("delivery")[-1])


# -- station state machines and lights -------------------------------------------------------

def test_bs_dispenses_base_and_runs_the_state_machine_with_lights(harness):
    h = harness().production()
    g = h.game
    assert h.station("C-BS").lights == GREEN and h.station("C-BS").state == "IDLE"
    assert g.prepare(CYAN, "C-BS", BSInstruction("OUTPUT", "BASE_RED"), CYAN) == "prepared"
    assert (h.station("C-BS").state, h.station("C-BS").lights) == ("PROCESSING", BUSY)
    h.run(1.0)                                              # dispensing: 1.1 s
    assert h.station("C-BS").state == "PROCESSING"
    h.run(2.5)                                              # the belt to the output: 2.656 s
    assert (h.station("C-BS").state, h.station("C-BS").lights) == ("PROCESSED", BUSY)
    assert h.world.workpiece_at("C-BS", "output") is None
    h.run(0.5)                                              # 3.756 s in all
    assert (h.station("C-BS").state, h.station("C-BS").lights) == ("READY-AT-OUTPUT", READY)
    assert h.world.workpiece_at("C-BS", "output") == Workpiece("BASE_RED")
    assert h.world.lights("C-BS") == READY
    assert h.world.take("C-BS", "output") == Workpiece("BASE_RED")
    h.run(0.25)
    assert (h.station("C-BS").state, h.station("C-BS").lights) == ("WAIT-IDLE", WAIT_IDLE)
    h.run(5)
    assert (h.station("C-BS").state, h.station("C-BS").lights) == ("IDLE", GREEN)
    assert states(h, "C-BS")[1:] == ["PREPARED", "PROCESSING", "PROCESSED", "READY-AT-OUTPUT",
                                     "WAIT-IDLE", "IDLE"]


def test_bs_input_side(harness):
    h = harness().production()
    h.game.prepare(MAGENTA, "M-BS", BSInstruction("INPUT", "BASE_SILVER"), MAGENTA)
    h.run(5.25)
    assert h.world.workpiece_at("M-BS", "input") == Workpiece("BASE_SILVER")
    h.world.take("M-BS", "input")
    h.run(0.25)
    assert h.station("M-BS").state == "WAIT-IDLE"


def test_prepared_blinks_green_for_3_s_and_waits_for_a_workpiece(harness):
    h = harness().production()
    h.game.prepare(CYAN, "C-DS", DSInstruction(2), CYAN)
    assert (h.station("C-DS").state, h.station("C-DS").lights) == ("PREPARED", GREEN_BLINK)
    h.run(3.25)
    assert (h.station("C-DS").state, h.station("C-DS").lights) == ("PREPARED", GREEN)
    h.run(60)
    assert h.station("C-DS").state == "PREPARED"


def test_2016_has_no_timeout_for_a_prepared_machine(harness):
    h = harness().production()
    h.game.prepare(CYAN, "C-RS1", RSInstruction(rs_color(h.game, "C-RS1", cost=0)), CYAN)
    h.run(120)
    assert h.station("C-RS1").state == "PREPARED"


def test_rs_mounts_a_free_ring(harness):
    h = harness().production()
    g = h.game
    color = rs_color(g, "C-RS1", cost=0)
    assert g.prepare(CYAN, "C-RS1", RSInstruction(color), CYAN) == "prepared"
    h.world.put("C-RS1", "input", Workpiece("BASE_BLACK"))
    h.run(0.25)
    assert (h.station("C-RS1").state, h.station("C-RS1").lights) == ("PROCESSING", BUSY)
    assert h.world.workpiece_at("C-RS1", "input") is None
    h.run(18.5)                                   # the belt (1.54 s), then mounting (17.31 s)
    assert h.station("C-RS1").state == "PROCESSING"
    h.run(0.25)
    assert h.station("C-RS1").state == "PROCESSED"
    h.run(2.5)                                    # the belt to the output (2.66 s): 21.50 s
    assert h.station("C-RS1").state == "PROCESSED"
    h.run(0.25)
    assert h.station("C-RS1").state == "READY-AT-OUTPUT"
    assert h.world.workpiece_at("C-RS1", "output") == Workpiece("BASE_BLACK", (color,))


def test_additional_bases_score_2_each_and_are_consumed_by_a_costly_ring(harness):
    h = harness(seed=4).production()
    g = h.game
    rs = next(r for r in ("C-RS1", "C-RS2") if any(g.ring_costs[c] == 2 for c in g.rs_colors(r)))
    color = rs_color(g, rs, cost=2)
    for _ in range(3):
        h.world.put(rs, "slide", Workpiece("BASE_RED"))
        h.run(0.25)
    assert h.world.workpiece_at(rs, "slide") is None and h.station(rs).slide_loaded == 3
    assert h.award_sum(CYAN) == 6
    g.prepare(CYAN, rs, RSInstruction(color), CYAN)
    h.world.put(rs, "input", Workpiece("BASE_RED"))
    h.run(22)
    assert h.world.workpiece_at(rs, "output") == Workpiece("BASE_RED", (color,))
    assert h.station(rs).slide_loaded == 1


def test_a_fourth_base_on_the_slide_breaks_the_rs(harness):
    h = harness().production()
    for _ in range(4):
        h.world.put("M-RS2", "slide", Workpiece("BASE_SILVER"))
        h.run(0.25)
    assert h.station("M-RS2").state == "BROKEN"
    assert h.award_sum(MAGENTA) == 6
    assert any("too many additional bases" in a for a in h.attention(MAGENTA))


def test_cs_retrieves_a_cap_then_mounts_it(harness):
    h = harness().production()
    g = h.game
    carrier = h.world.take("C-CS1", "shelf0")
    assert carrier.cap == "CAP_GREY"
    h.run(0.25)
    assert h.world.workpiece_at("C-CS1", "shelf0") is None     # refilled only once empty
    assert g.prepare(CYAN, "C-CS1", CSInstruction("RETRIEVE_CAP"), CYAN) == "prepared"
    h.world.put("C-CS1", "input", carrier)
    h.run(22)
    assert h.world.workpiece_at("C-CS1", "output") == Workpiece(carrier.base)
    assert h.station("C-CS1").cap_buffer == "CAP_GREY"
    h.world.take("C-CS1", "output")
    h.run(5.25)
    assert h.station("C-CS1").state == "IDLE"
    assert g.prepare(CYAN, "C-CS1", CSInstruction("MOUNT_CAP"), CYAN) == "prepared"
    h.world.put("C-CS1", "input", Workpiece("BASE_BLACK", ("RING_BLUE",)))
    h.run(22)
    assert h.world.workpiece_at("C-CS1", "output") == Workpiece("BASE_BLACK", ("RING_BLUE",),
                                                                "CAP_GREY")
    assert h.station("C-CS1").cap_buffer is None


# -- wrong instructions break the station ---------------------------------------------------

def test_wrong_rs_colour_breaks_and_recovers_after_30_s_with_the_slide_cleared(harness):
    h = harness().production()
    g = h.game
    h.world.put("C-RS2", "slide", Workpiece("BASE_RED"))
    h.run(0.25)
    wrong = next(c for c in g.ring_costs if c not in g.rs_colors("C-RS2"))
    assert g.prepare(CYAN, "C-RS2", RSInstruction(wrong), CYAN) == "broken"
    assert (h.station("C-RS2").state, h.station("C-RS2").lights) == ("BROKEN", BROKEN)
    assert any("invalid ring color" in a for a in h.attention(CYAN))
    h.run(29.75)
    assert h.station("C-RS2").state == "BROKEN"
    h.run(0.5)
    assert (h.station("C-RS2").state, h.station("C-RS2").lights) == ("IDLE", GREEN)
    assert h.station("C-RS2").slide_loaded == 0


@pytest.mark.parametrize("machine,instr", [
    ("C-BS", None), ("C-RS1", None), ("C-CS2", None), ("C-DS", None),
    ("C-BS", RSInstruction("RING_BLUE")),                 # an instruction for another type
    ("C-BS", BSInstruction("OUTPUT", "CAP_GREY")),
])
def test_missing_or_invalid_instruction_breaks(harness, machine, instr):
    h = harness().production()
    assert h.game.prepare(CYAN, machine, instr, CYAN) == "broken"
    assert h.station(machine).state == "BROKEN"


def test_cs_operation_against_the_buffer_breaks(harness):
    h = harness().production()
    g = h.game
    assert g.prepare(CYAN, "C-CS2", CSInstruction("MOUNT_CAP"), CYAN) == "broken"
    assert "Prepare received for C-CS2: cannot mount without cap" in h.attention(CYAN)
    h.station("C-CS1").cap_buffer = "CAP_GREY"
    assert g.prepare(CYAN, "C-CS1", CSInstruction("RETRIEVE_CAP"), CYAN) == "broken"
    assert any("already holding" in a for a in h.attention(CYAN))


def test_rs_without_the_additional_bases_breaks_when_fed(harness):
    h = harness().production()
    g = h.game
    rs = next(r for r in ("C-RS1", "C-RS2") if any(g.ring_costs[c] > 0 for c in g.rs_colors(r)))
    costly = next(c for c in g.rs_colors(rs) if g.ring_costs[c] > 0)
    assert g.prepare(CYAN, rs, RSInstruction(costly), CYAN) == "prepared"
    h.world.put(rs, "input", Workpiece("BASE_RED"))
    h.run(0.25)
    assert h.station(rs).state == "BROKEN"
    assert h.world.workpiece_at(rs, "input") is None                   # taken off by the referee
    assert any("insufficient bases" in a for a in h.attention(CYAN))


def test_cs_retrieve_from_a_capless_workpiece_breaks(harness):
    h = harness().production()
    h.game.prepare(CYAN, "C-CS1", CSInstruction("RETRIEVE_CAP"), CYAN)
    h.world.put("C-CS1", "input", Workpiece("BASE_RED"))
    h.run(0.25)
    assert h.station("C-CS1").state == "BROKEN"


# -- PrepareMachine that is ignored ---------------------------------------------------------

def test_prepare_out_of_phase_or_paused_is_ignored(harness):
    h = harness()
    g = h.game
    instr = BSInstruction("OUTPUT", "BASE_RED")
    assert g.prepare(CYAN, "C-BS", instr, CYAN).startswith("ignored")            # PRE_GAME
    g.start()
    assert g.prepare(CYAN, "C-BS", instr, CYAN).startswith("ignored")            # SETUP
    g.set_phase("EXPLORATION")
    assert g.prepare(CYAN, "C-BS", instr, CYAN).startswith("ignored")
    g.set_phase("PRODUCTION")
    g.set_state("PAUSED")
    assert g.prepare(CYAN, "C-BS", instr, CYAN).startswith("ignored")
    assert h.station("C-BS").state == "IDLE"
    g.set_state("RUNNING")
    assert g.prepare(CYAN, "C-BS", instr, CYAN) == "prepared"


def test_prepare_for_another_teams_machine_or_on_the_wrong_channel_is_ignored(harness):
    h = harness().production()
    g = h.game
    instr = BSInstruction("OUTPUT", "BASE_RED")
    assert g.prepare(CYAN, "M-BS", instr, CYAN) == "ignored: not a machine of that team"
    assert any("invalid machine M-BS" in a for a in h.attention(CYAN))
    assert g.prepare(CYAN, "C-BS", instr, channel_team=MAGENTA) == "ignored: wrong channel"
    assert any("Invalid prepare for team CYAN of team MAGENTA" in a for a in h.attention(MAGENTA))
    assert g.prepare(CYAN, "C-XX", instr, CYAN).startswith("ignored")
    assert h.station("M-BS").state == h.station("C-BS").state == "IDLE"


def test_prepare_for_a_busy_station_is_ignored(harness):
    h = harness().production()
    g = h.game
    g.prepare(CYAN, "C-BS", BSInstruction("OUTPUT", "BASE_RED"), CYAN)
    assert g.prepare(CYAN, "C-BS", None, CYAN) == "ignored: C-BS is PROCESSING"
    assert h.station("C-BS").state == "PROCESSING"


# -- down periods ------------------------------------------------------------------------

def test_down_period_shows_red_and_delays_processing(harness):
    h = harness().production()
    g = h.game
    color = rs_color(g, "C-RS1", cost=0)
    st = h.station("C-RS1")
    st.down = (5.0, 25.0)
    g.prepare(CYAN, "C-RS1", RSInstruction(color), CYAN)
    h.world.put("C-RS1", "input", Workpiece("BASE_RED"))
    h.run(5.25)
    assert (st.state, st.lights) == ("DOWN", DOWN)
    assert g.prepare(CYAN, "C-RS1", RSInstruction(color), CYAN).startswith("ignored")
    h.run(20)
    assert (st.state, st.lights) == ("PROCESSING", BUSY)           # back, 20 s later
    h.run(13.5)
    assert st.state == "PROCESSING"                               # 1.5 + 17.3 s + 20 s down
    h.run(0.25)
    assert st.state == "PROCESSED"
    h.run(2.5)
    assert st.state == "PROCESSED"
    h.run(0.25)
    assert st.state == "READY-AT-OUTPUT"


# -- delivery and product points ---------------------------------------------------------------

def _open_order(g, idx, *, begin=0, end=900, gate=None):
    o = g.orders[idx]
    o.active, o.begin, o.end = True, begin, end
    if gate is not None:
        o.gate = gate
    return o


def _product(o):
    return Workpiece(o.base, o.rings, o.cap)


def test_delivery_in_window_scores_20_plus_cap(harness):
    h = harness().production()
    o = _open_order(h.game, 0)
    pts, ev = deliver(h, _product(o), o.gate)
    assert pts == 20 + 10 and ev.data["how"] == "in-time" and o.delivered[CYAN] == 1
    assert h.game.points(CYAN) == 30


@pytest.mark.parametrize("late,expected", [(0.0, 20), (4.5, 14), (9.75, 6)])
def test_late_delivery_within_10_s_reduced(harness, late, expected):
    h = harness().production()
    o = _open_order(h.game, 0)
    o.end = T.delivery(o.gate) - late    # deliver() finishes after the gate's slot time
    pts, ev = deliver(h, _product(o), o.gate)
    assert pts == expected + 10
    assert ev.data["how"] == ("in-time" if late == 0 else "late")


def test_too_late_delivery_scores_5(harness):
    h = harness().production()
    o = _open_order(h.game, 0)
    h.run(30)
    o.end = 10
    pts, ev = deliver(h, _product(o), o.gate)
    assert ev.data["how"] == "too-late" and pts == 5 + 10


def test_wrong_product_scores_nothing_and_raises_attention(harness):
    h = harness().production()
    _open_order(h.game, 0)
    pts, ev = deliver(h, Workpiece("BASE_RED", ("RING_BLUE", "RING_BLUE", "RING_BLUE")), 1)
    assert pts == 0 and ev.data["how"] == "no-order"
    assert any("Invalid order delivered" in a for a in h.attention(CYAN))


def test_wrong_gate_and_too_many_score_1(harness):
    h = harness().production()
    o = _open_order(h.game, 0, gate=2)
    pts, ev = deliver(h, _product(o), 3)
    assert (pts, ev.data["how"]) == (1, "wrong-gate") and o.delivered[CYAN] == 0
    assert deliver(h, _product(o), 0)[0] == 30                       # gate 0: any gate
    pts, ev = deliver(h, _product(o), 2)
    assert (pts, ev.data["how"]) == (1, "too-many")


def test_too_soon_delivery_scores_nothing(harness):
    h = harness().production()
    o = _open_order(h.game, 0, begin=100, end=200)
    pts, ev = deliver(h, _product(o), o.gate)
    assert (pts, ev.data["how"]) == (0, "too-soon") and o.delivered[CYAN] == 0


@pytest.mark.parametrize("idx,costs,expected", [
    (4, (0,), 20 + 5 + 10 + 10),                     # C1, CC0 ring, pre-cap 10, cap
    (4, (1,), 20 + 10 + 10 + 10),                    # C1, CC1 ring
    (4, (2,), 20 + 20 + 10 + 10),                    # C1, CC2 ring
    (5, (0, 1), 20 + 5 + 10 + 30 + 10),              # C2, pre-cap 30
    (6, (2, 0, 1), 20 + 20 + 5 + 10 + 80 + 10),      # C3, pre-cap 80
])
def test_ring_steps_by_cost_precap_by_complexity_and_cap(harness, idx, costs, expected):
    h = harness(seed=6).production()
    g = h.game
    o = _open_order(g, idx)
    g.ring_costs = dict(g.ring_costs)
    for color, cost in zip(o.rings, costs):
        g.ring_costs[color] = cost
    pts, ev = deliver(h, _product(o), o.gate)
    assert ev.data["how"] == "in-time" and pts == expected


def test_magenta_delivery_counts_for_magenta(harness):
    h = harness().production()
    o = _open_order(h.game, 0)
    pts, _ = deliver(h, _product(o), o.gate, team=MAGENTA)
    assert pts == 30 and o.delivered == {CYAN: 0, MAGENTA: 1}
    assert h.game.points(MAGENTA) == 30 and h.game.points(CYAN) == 0


def test_orders_activate_over_production_time(harness):
    h = harness(seed=3, production=120).production()
    g = h.game
    at_start = [o.id for o in g.active_orders()]
    assert 1 in at_start and 7 in at_start             # the standing order and the C3
    assert at_start == [o.id for o in g.orders if o.activate_at == 0 and not o.overtime]
    h.run(119)
    assert [o.id for o in g.active_orders()] == list(range(1, 8))      # #8 waits for overtime
    acts = {e.data["order"]: e.game_time for e in h.events("order")}
    for o in g.orders[:7]:
        assert acts[o.id] == pytest.approx(o.activate_at, abs=0.26)


def test_full_c1_production_chain(harness):
    """BS -> RS (with the ring's additional bases) -> CS retrieve and mount -> DS."""
    h = harness(seed=8).production()
    g, w = h.game, h.world
    o = _open_order(g, 4)
    ring = o.rings[0]
    rs = next(r for r in ("C-RS1", "C-RS2") if ring in g.rs_colors(r))
    cs = "C-CS1" if o.cap == "CAP_GREY" else "C-CS2"
    cost = g.ring_costs[ring]

    def take_when_ready(machine, slot="output"):
        for _ in range(200):
            if h.station(machine).state == "READY-AT-OUTPUT":
                return w.take(machine, slot)
            h.run(0.25)
        raise AssertionError(f"{machine} never got ready ({h.station(machine).state})")

    for _ in range(cost):                            # bases for the slide from the BS
        g.prepare(CYAN, "C-BS", BSInstruction("OUTPUT", "BASE_BLACK"), CYAN)
        w.put(rs, "slide", take_when_ready("C-BS"))
        h.run(5.25)
    g.prepare(CYAN, "C-BS", BSInstruction("OUTPUT", o.base), CYAN)
    wp = take_when_ready("C-BS")
    h.run(5.25)
    assert g.prepare(CYAN, rs, RSInstruction(ring), CYAN) == "prepared"
    w.put(rs, "input", wp)
    wp = take_when_ready(rs)
    assert g.prepare(CYAN, cs, CSInstruction("RETRIEVE_CAP"), CYAN) == "prepared"
    w.put(cs, "input", w.take(cs, "shelf1"))
    take_when_ready(cs)                              # the cap-less carrier
    h.run(5.25)
    assert g.prepare(CYAN, cs, CSInstruction("MOUNT_CAP"), CYAN) == "prepared"
    w.put(cs, "input", wp)
    wp = take_when_ready(cs)
    assert wp == _product(o)
    pts, ev = deliver(h, wp, o.gate)
    assert ev.data["how"] == "in-time"
    assert pts == 20 + (5, 10, 20)[cost] + 10 + 10
    assert g.points(CYAN) == 2 * cost + pts


def test_profiles_that_require_a_report_refuse_prepare_until_reported():
    """The hook a 2025 rule set relies on, exercised with a 2016 profile variant."""
    from dataclasses import replace

    from backends.sim.refbox import RefboxGame, ReportEntry
    from rll_bt.clock import SimClock
    from rll_bt.rules import profile
    prof = replace(profile("rcll2016"), prepare_requires_report=True)
    g = RefboxGame(prof, SimClock(), seed=2, team_cyan="Caro", team_magenta="Grips")
    g.start()
    g.set_phase("EXPLORATION")
    ex = g.exploration
    g.machine_report(CYAN, [ReportEntry("C-BS", ex.expected_type("C-BS"),
                                        g.layout.machines["C-BS"].zone)], CYAN)
    g.set_phase("PRODUCTION")
    instr = DSInstruction(1)
    assert g.prepare(CYAN, "C-DS", instr, CYAN) == "ignored: C-DS is not yet correctly reported"
    assert g.prepare(CYAN, "C-BS", BSInstruction("OUTPUT", "BASE_RED"), CYAN) == "prepared"
