"""2025 production: the points table, delivery by order id, the storage station,
ResetMachine, the PrepareMachine rules of today's refbox and the 2019+ light table."""
from __future__ import annotations

import pytest

from backends.sim.refbox import (
    BSInstruction,
    CSInstruction,
    DSInstruction,
    ReportEntry,
    RSInstruction,
    SSInstruction,
    StationConfig,
    Workpiece,
)
from backends.sim.refbox.messages import Messages, enum_name
from rll_bt.rules import CYAN, MAGENTA, MPS_TIMES

T = MPS_TIMES
M25 = Messages("rcll2025")
GREEN = {"RED": "OFF", "YELLOW": "OFF", "GREEN": "ON"}
GREEN_BLINK = {"RED": "OFF", "YELLOW": "OFF", "GREEN": "BLINK"}
READY = {"RED": "OFF", "YELLOW": "ON", "GREEN": "BLINK"}
WAIT_IDLE = {"RED": "OFF", "YELLOW": "BLINK", "GREEN": "BLINK"}


def open_game(harness25, **kw):
    """A 2025 game in PRODUCTION with the ground truth out (every station usable)."""
    return harness25(exploration=0, **kw).production()


def set_order(g, oid, cx, rings=None, competitive=False, begin=0, end=1000):
    """Make order ``oid`` an active C``cx`` order with ``rings`` (default: the first free
    colours) and return it with the workpiece that fulfils it."""
    o = g.order(oid)
    o.complexity, o.rings = cx, tuple(rings if rings is not None else
                                      sorted(g.ring_costs, key=g.ring_costs.get)[:cx])
    o.competitive, o.begin, o.end, o.active = competitive, begin, end, True
    return o, Workpiece(o.base, o.rings, o.cap)


def deliver(h, wp, order_id, team=CYAN):
    """One DS cycle for ``order_id``; returns (points it scored, the delivery event)."""
    ds = f"{'C' if team == CYAN else 'M'}-DS"
    n = len(h.game.ledger.entries)
    assert h.game.prepare(team, ds, DSInstruction(order_id=order_id), team) == "prepared"
    h.world.put(ds, "input", wp)
    h.run(10)                       # the gate's slot (<= 4.75 s), then WAIT-IDLE for 5 s
    assert h.station(ds).state == "IDLE" and h.world.workpiece_at(ds, "input") is None
    return sum(e.points for e in h.game.ledger.entries[n:]), h.events("delivery")[-1]


# -- points --------------------------------------------------------------------------

@pytest.mark.parametrize("cx,points", [(0, 20), (1, 30), (2, 50), (3, 100)])
def test_delivery_points_by_complexity_plus_ring_steps_and_cap(harness25, cx, points):
    h = open_game(harness25, seed=2)
    g = h.game
    o, wp = set_order(g, 3, cx)
    rings = sum((5, 10, 20)[g.ring_costs[c]] for c in o.rings)
    pts, ev = deliver(h, wp, 3)
    assert ev.data["how"] == "in-time" and ev.data["order"] == 3
    assert ev.text.endswith(f"at gate {o.gate}: in-time")          # the gate of the order
    assert pts == points + rings + 10
    reasons = [e.reason for e in h.awards(CYAN)]
    assert "mounted cap for order 3" in reasons and not any("last ring" in r for r in reasons)
    assert o.delivered == {CYAN: 1, MAGENTA: 0}


def test_ring_steps_score_by_the_colours_cost(harness25):
    h = open_game(harness25, seed=5)
    g = h.game
    by_cost = sorted(g.ring_costs, key=g.ring_costs.get)            # costs 0, 0, 1, 2
    o, wp = set_order(g, 4, 2, rings=(by_cost[3], by_cost[2]))     # CC2 then CC1
    pts, _ = deliver(h, wp, 4)
    assert pts == 50 + 20 + 10 + 10


@pytest.mark.parametrize("late,points", [(0, 50), (1, 41), (44, 41), (46, 32), (89, 32),
                                         (91, 22), (134, 22), (136, 13), (600, 13)])
def test_late_delivery_loses_a_quarter_step_of_75_percent_per_quarter_window(harness25, late,
                                                                             points):
    """2025 (orders.clp): late by up to 1/4, 2/4, 3/4 of the window's length (180 s here)
    costs 18.75 %, 37.5 %, 56.25 % of the delivery points, later 75 %; the step points
    are paid in full."""
    h = open_game(harness25)
    g = h.game
    h.run(100)
    o, wp = set_order(g, 5, 2)
    t = 100 + T.delivery(o.gate)                                    # delivered then
    o.end = t - late
    o.begin = o.end - 180
    pts, ev = deliver(h, wp, 5)
    assert ev.game_time == pytest.approx(t)
    rings = sum((5, 10, 20)[g.ring_costs[c]] for c in o.rings)
    assert pts == points + rings + 10
    assert ev.data["how"] == ("in-time" if late == 0 else "late")


def test_a_c3_delivered_40_s_late_scores_82_delivery_points(harness25):
    h = open_game(harness25, seed=3)
    g = h.game
    h.run(300)
    o, wp = set_order(g, 4, 3, rings=g.rs_colors("C-RS1") + g.rs_colors("C-RS2")[:1])
    t = 300 + T.delivery(o.gate)
    o.end, o.begin = t - 40, t - 40 - 180
    _, ev = deliver(h, wp, 4)
    delivery = [e for e in h.awards(CYAN) if e.reason.startswith("delivered item for order 4")]
    assert [e.points for e in delivery] == [82] and ev.data["how"] == "late"


def test_competitive_order_first_gains_10_second_loses_10(harness25):
    h = open_game(harness25)
    g = h.game
    o, wp = set_order(g, 6, 0, competitive=True)
    first, _ = deliver(h, wp, 6, CYAN)
    second, _ = deliver(h, wp, 6, MAGENTA)
    assert first == 20 + 10 + 10 and second == 20 - 10 + 10
    assert "first delivery for competitive order 6" in [e.reason for e in h.awards(CYAN)]
    assert "second delivery for competitive order 6" in [e.reason for e in h.awards(MAGENTA)]


def test_additional_base_scores_2_and_cap_retrieval_scores_2(harness25):
    h = open_game(harness25)
    g = h.game
    h.world.put("C-RS2", "slide", Workpiece("BASE_RED"))
    h.run(0.25)
    assert h.award_sum(CYAN) == 2 and h.station("C-RS2").slide_loaded == 1
    assert g.prepare(CYAN, "C-CS1", CSInstruction("RETRIEVE_CAP"), CYAN) == "prepared"
    h.world.put("C-CS1", "input", h.world.take("C-CS1", "shelf0"))
    h.run(22)
    assert h.station("C-CS1").cap_buffer == "CAP_GREY"
    assert [(e.points, e.reason) for e in h.awards(CYAN)][-1] == (2, "retrieved cap at C-CS1")
    assert g.points(CYAN) == 4


# -- delivery station by order id --------------------------------------------------------

def test_order_id_0_only_consumes_the_workpiece(harness25):
    h = open_game(harness25)
    pts, ev = deliver(h, Workpiece("BASE_BLACK"), 0)
    assert pts == 0 and ev.data["how"] == "consumed" and not h.awards(CYAN)


def test_unknown_order_id_breaks_the_ds(harness25):
    h = open_game(harness25)
    assert h.game.prepare(CYAN, "C-DS", DSInstruction(order_id=99), CYAN) == "broken"
    assert h.station("C-DS").broken_reason == "Prepare received for C-DS with invalid order ID"
    h.run(30.25)
    assert h.station("C-DS").state == "IDLE"
    assert h.game.prepare(CYAN, "C-DS", DSInstruction(gate=2), CYAN) == "broken"   # no order id


def test_wrong_product_inactive_order_and_too_many(harness25):
    h = open_game(harness25)
    g = h.game
    o, wp = set_order(g, 7, 1)
    wrong = Workpiece(wp.base, wp.rings, "CAP_BLACK" if wp.cap == "CAP_GREY" else "CAP_GREY")
    pts, ev = deliver(h, wrong, 7)
    assert (pts, ev.data["how"]) == (0, "wrong-product")
    assert any("Incorrect delivery for order 7" in t for t in h.attention(CYAN))
    later = next(x for x in g.orders if not x.active and x.id != 11)
    later.begin = 0
    pts, ev = deliver(h, Workpiece(later.base, later.rings, later.cap), later.id)
    assert (pts, ev.data["how"]) == (0, "no-order")
    deliver(h, wp, 7)
    pts, ev = deliver(h, wp, 7)
    assert (pts, ev.data["how"]) == (0, "too-many") and o.delivered[CYAN] == 2


def test_the_ds_does_not_take_a_product_before_its_window_and_breaks_after_20_s(harness25):
    """2025: a DS prepared for an order whose window has not opened stays PREPARED with the
    product on its input; 20 s after the prepare it is BROKEN and the product is lost."""
    h = open_game(harness25)
    g = h.game
    o, wp = set_order(g, 7, 1, begin=500, end=900)
    assert g.prepare(CYAN, "C-DS", DSInstruction(order_id=7), CYAN) == "prepared"
    h.world.put("C-DS", "input", wp)
    h.run(19.75)
    assert h.station("C-DS").state == "PREPARED" and h.world.workpiece_at("C-DS", "input") == wp
    h.run(0.5)
    assert h.station("C-DS").state == "BROKEN" and h.station("C-DS").broken_cause == "timeout"
    assert h.world.workpiece_at("C-DS", "input") is None and not h.events("delivery")
    assert o.delivered[CYAN] == 0


def test_unconfirmed_deliveries_are_listed_until_the_referee_confirms(harness25):
    h = open_game(harness25, config=StationConfig(delivery_confirm=20.0))
    g = h.game
    o, wp = set_order(g, 3, 0)
    pts, ev = deliver(h, wp, 3)
    assert pts == 0 and ev.data["how"] == "unconfirmed"
    oi = M25.order_info(g)
    u = next(x for x in oi.orders if x.id == 3).unconfirmed_deliveries
    at = T.delivery(o.gate)
    assert [(d.id, enum_name(d, "team"), d.delivery_time.sec) for d in u] == [(1, "CYAN", int(at))]
    h.run(20)
    assert not g.pending_deliveries and h.award_sum(CYAN) == 30
    assert {e.game_time for e in h.awards(CYAN)} == {at}              # scored at delivery time
    assert not next(x for x in M25.order_info(g).orders if x.id == 3).unconfirmed_deliveries


# -- storage station ----------------------------------------------------------------------

def test_ss_stores_and_retrieves_a_workpiece_for_5_points_each(harness25):
    h = open_game(harness25)
    g = h.game
    ss = h.station("C-SS")
    wp = Workpiece("BASE_BLACK", ("RING_BLUE",), None)
    assert g.prepare(CYAN, "C-SS", SSInstruction("STORE", 2, 5, "half a C1"), CYAN) == "prepared"
    h.world.put("C-SS", "input", wp)
    h.run(0.25)
    assert ss.state == "PREPARED" and h.world.workpiece_at("C-SS", "input") is None  # to the middle
    h.run(1.5)
    assert ss.state == "PROCESSING"
    h.run(17.5)                                          # 1.54 + 17.5 s: stored
    assert ss.state == "WAIT-IDLE" and ss.stored()[(2, 5)] == wp
    assert [(e.points, e.reason) for e in h.awards(CYAN)] == [
        (-5, "payment for storing (2, 5) at C-SS")]
    h.run(5)
    assert ss.state == "IDLE"
    status = next(m for m in M25.machine_info(g, CYAN).machines if m.name == "C-SS").status_ss
    assert len(status) == 48
    assert (2, 5, "half a C1") in [(s.shelf, s.slot, s.description) for s in status if s.is_filled]
    assert g.prepare(CYAN, "C-SS", SSInstruction("RETRIEVE", 2, 5), CYAN) == "prepared"
    assert ss.state == "PROCESSING"                       # nothing to feed
    h.run(17.25)
    assert ss.state == "PROCESSING"
    h.run(0.5)
    assert ss.state == "PROCESSED" and (2, 5) not in ss.stored()
    h.run(2.5)                                            # 17.5 + 2.66 s: at the output
    assert ss.state == "READY-AT-OUTPUT" and h.world.workpiece_at("C-SS", "output") == wp
    assert ss.lights == READY and h.award_sum(CYAN) == -10
    h.world.take("C-SS", "output")
    h.run(0.25)
    assert ss.state == "WAIT-IDLE" and ss.lights == WAIT_IDLE
    h.run(5)
    assert ss.state == "IDLE"


def test_ss_change_info_and_the_instructions_that_break_it(harness25):
    h = open_game(harness25)
    g = h.game
    ss = h.station("C-SS")
    ss.put_in_storage(0, 0, Workpiece("BASE_RED"), "old")
    assert g.prepare(CYAN, "C-SS", SSInstruction("CHANGE_INFO", 0, 0, "new"), CYAN) == "done"
    assert ss.state == "IDLE" and ss.place(0, 0).description == "new"
    for instr, why in ((SSInstruction("STORE", 0, 0), "occupied"),
                       (SSInstruction("RETRIEVE", 1, 3), "empty"),
                       (SSInstruction("RETRIEVE", 6, 0), "invalid shelf or slot"),
                       (SSInstruction("STORE", 0, 8), "invalid shelf or slot")):
        assert g.prepare(CYAN, "C-SS", instr, CYAN) == "broken"
        assert why in ss.broken_reason
        h.run(30.25)
        assert ss.state == "IDLE" and ss.stored()[(0, 0)] == Workpiece("BASE_RED")


# -- ResetMachine, PrepareMachine rules ---------------------------------------------------

def test_reset_machine_breaks_the_station_for_the_broken_time(harness25):
    h = open_game(harness25)
    g = h.game
    assert g.reset_machine(CYAN, "C-RS1", CYAN) == "broken"
    assert h.station("C-RS1").state == "BROKEN"
    assert "Machine C-RS1 resetted by the team CYAN" in h.attention(CYAN)[-1]
    h.run(29.75)
    assert h.station("C-RS1").state == "BROKEN"
    h.run(0.5)
    assert h.station("C-RS1").state == "IDLE"
    assert g.reset_machine(CYAN, "C-RS1", MAGENTA) == "ignored: wrong channel"
    assert "Invalid reset for team CYAN of team MAGENTA" in h.attention(MAGENTA)[-1]
    assert g.reset_machine(CYAN, "M-RS1", CYAN) == "ignored: not a machine of that team"
    assert "Reset received for invalid machine M-RS1" in h.attention(CYAN)[-1]


def test_reset_while_down_breaks_once_the_station_is_up(harness25):
    h = open_game(harness25, seed=3)
    name, st = next((n, s) for n, s in sorted(h.game.stations.items()) if s.down)
    start, end = st.down
    h.run(start + 0.25)
    assert st.state == "DOWN"
    h.game.reset_machine(st.team, name, st.team)
    assert st.state == "DOWN"
    h.run(end - start)
    assert st.state == "BROKEN"
    h.run(30)
    assert st.state == "IDLE"


def test_prepare_refused_until_correctly_reported(harness25):
    h = harness25().production()
    g = h.game
    bs = BSInstruction("OUTPUT", "BASE_RED")
    assert g.prepare(CYAN, "C-BS", bs, CYAN) == "ignored: C-BS is not yet correctly reported"
    assert "C-BS is not yet correctly reported" in h.attention(CYAN)[-1]
    z = g.layout.zone("C-BS")
    g.machine_report(CYAN, [ReportEntry("C-BS", None, z, None)], CYAN)   # zone only
    assert g.prepare(CYAN, "C-BS", bs, CYAN).startswith("ignored")
    g.machine_report(CYAN, [ReportEntry("C-BS", None, None, g.layout.rotation("C-BS"))], CYAN)
    assert g.prepare(CYAN, "C-BS", bs, CYAN) == "prepared"


def test_prepare_sent_more_than_5_s_ago_is_ignored(harness25):
    h = open_game(harness25)
    g = h.game
    now = h.clock.epoch()
    bs = BSInstruction("OUTPUT", "BASE_RED")
    assert g.prepare(CYAN, "C-BS", bs, CYAN, sent_at=now - 6).startswith("ignored: sent 6 s ago")
    assert h.station("C-BS").state == "IDLE"
    assert g.prepare(CYAN, "C-BS", bs, CYAN, sent_at=now - 4) == "prepared"
    assert g.prepare(MAGENTA, "M-BS", bs, MAGENTA) == "prepared"          # no sent_at


def test_missing_instruction_breaks_and_prepare_at_ready_is_ignored(harness25):
    """production-prepare-*: "Prepare received for X without data"; a prepare for a machine
    that is not IDLE is ignored, READY-AT-OUTPUT too (refbox commit 78b464b9)."""
    h = open_game(harness25)
    g = h.game
    assert g.prepare(CYAN, "C-RS1", None, CYAN) == "broken"
    assert h.station("C-RS1").broken_reason == "Prepare received for C-RS1 without data"
    g.prepare(CYAN, "C-BS", BSInstruction("OUTPUT", "BASE_RED"), CYAN)
    h.run(4)
    assert h.station("C-BS").state == "READY-AT-OUTPUT" and h.station("C-BS").lights == READY
    assert g.prepare(CYAN, "C-BS", BSInstruction("OUTPUT", "BASE_RED"), CYAN) == \
        "ignored: C-BS is READY-AT-OUTPUT"
    assert h.world.workpiece_at("C-BS", "output") == Workpiece("BASE_RED")


def test_prepared_blinks_green_until_fed(harness25):
    h = open_game(harness25)
    g = h.game
    color = next(c for c in g.rs_colors("C-RS1") if g.ring_costs[c] == 0)
    assert g.prepare(CYAN, "C-RS1", RSInstruction(color), CYAN) == "prepared"
    h.run(10)
    assert h.station("C-RS1").lights == GREEN_BLINK and h.world.lights("C-RS1") == GREEN_BLINK
    assert h.station("C-DS").lights == GREEN


def test_no_station_goes_down_before_the_exploration_time(harness25):
    for seed in range(4):
        h = harness25(seed=seed, production=400, exploration=100).production()
        h.run(100)
        assert not [e for e in h.events("machine") if e.data["state"] == "DOWN"]
        h.run(300)
        downs = [e for e in h.events("machine") if e.data["state"] == "DOWN"]
        assert len(downs) == 4 and min(e.game_time for e in downs) >= 100
