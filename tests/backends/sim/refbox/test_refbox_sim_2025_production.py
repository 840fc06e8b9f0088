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
from rll_bt.rules import CYAN, MAGENTA

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
    h.run(8.25)
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


@pytest.mark.parametrize("late,points", [(0, 50), (3, 45), (4, 44), (10, 35), (11, 5), (60, 5)])
def test_late_delivery_deductions(harness25, late, points):
    h = open_game(harness25)
    g = h.game
    h.run(100)
    o, wp = set_order(g, 5, 2, end=100 + 8 - late)                  # delivered at 108
    pts, ev = deliver(h, wp, 5)
    assert ev.game_time == 108
    rings = sum((5, 10, 20)[g.ring_costs[c]] for c in o.rings)
    assert pts == points + rings + 10
    assert ev.data["how"] == ("in-time" if late == 0 else "late" if late <= 10 else "too-late")


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
    h.run(12.25)
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
    assert "invalid order ID 99" in h.station("C-DS").broken_reason
    h.run(30.25)
    assert h.station("C-DS").state == "IDLE"
    assert h.game.prepare(CYAN, "C-DS", DSInstruction(gate=2), CYAN) == "broken"   # no order id


def test_wrong_product_inactive_order_too_soon_and_too_many(harness25):
    h = open_game(harness25)
    g = h.game
    o, wp = set_order(g, 7, 1, begin=500, end=900)
    wrong = Workpiece(wp.base, wp.rings, "CAP_BLACK" if wp.cap == "CAP_GREY" else "CAP_GREY")
    pts, ev = deliver(h, wrong, 7)
    assert (pts, ev.data["how"]) == (0, "wrong-product")
    assert any("Incorrect delivery for order 7" in t for t in h.attention(CYAN))
    pts, ev = deliver(h, wp, 7)
    assert (pts, ev.data["how"]) == (0, "too-soon")
    assert o.delivered[CYAN] == 0
    later = next(x for x in g.orders if not x.active and x.id != 11)
    pts, ev = deliver(h, Workpiece(later.base, later.rings, later.cap), later.id)
    assert (pts, ev.data["how"]) == (0, "no-order")
    o.begin = 0
    deliver(h, wp, 7)
    pts, ev = deliver(h, wp, 7)
    assert (pts, ev.data["how"]) == (0, "too-many") and o.delivered[CYAN] == 2


def test_unconfirmed_deliveries_are_listed_until_the_referee_confirms(harness25):
    h = open_game(harness25, config=StationConfig(delivery_confirm=20.0))
    g = h.game
    o, wp = set_order(g, 3, 0)
    pts, ev = deliver(h, wp, 3)
    assert pts == 0 and ev.data["how"] == "unconfirmed"
    oi = M25.order_info(g)
    u = next(x for x in oi.orders if x.id == 3).unconfirmed_deliveries
    assert [(d.id, enum_name(d, "team"), d.delivery_time.sec) for d in u] == [(1, "CYAN", 8)]
    h.run(20)
    assert not g.pending_deliveries and h.award_sum(CYAN) == 30
    assert {e.game_time for e in h.awards(CYAN)} == {8}               # scored at delivery time
    assert not next(x for x in M25.order_info(g).orders if x.id == 3).unconfirmed_deliveries


# -- storage station ----------------------------------------------------------------------

def test_ss_stores_and_retrieves_a_workpiece(harness25):
    h = open_game(harness25)
    g = h.game
    ss = h.station("C-SS")
    wp = Workpiece("BASE_BLACK", ("RING_BLUE",), None)
    assert g.prepare(CYAN, "C-SS", SSInstruction("STORE", 2, 5, "half a C1"), CYAN) == "prepared"
    h.world.put("C-SS", "input", wp)
    h.run(0.25)
    assert ss.state == "PROCESSING" and h.world.workpiece_at("C-SS", "input") is None
    h.run(10)
    assert ss.state == "IDLE" and ss.stored() == {(2, 5): wp}
    status = next(m for m in M25.machine_info(g, CYAN).machines if m.name == "C-SS").status_ss
    assert len(status) == 48
    assert [(s.shelf, s.slot, s.description) for s in status if s.is_filled] == \
        [(2, 5, "half a C1")]
    assert g.prepare(CYAN, "C-SS", SSInstruction("RETRIEVE", 2, 5), CYAN) == "prepared"
    assert ss.state == "PROCESSING"                       # nothing to feed
    h.run(10.25)
    assert ss.state == "READY-AT-OUTPUT" and h.world.workpiece_at("C-SS", "output") == wp
    assert ss.lights == READY and ss.stored() == {}
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
                       (SSInstruction("RETRIEVE", 1, 1), "empty"),
                       (SSInstruction("RETRIEVE", 6, 0), "invalid shelf or slot"),
                       (SSInstruction("STORE", 0, 8), "invalid shelf or slot")):
        assert g.prepare(CYAN, "C-SS", instr, CYAN) == "broken"
        assert why in ss.broken_reason
        h.run(30.25)
        assert ss.state == "IDLE" and ss.stored() == {(0, 0): Workpiece("BASE_RED")}


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


def test_missing_instruction_is_ignored_and_prepare_at_ready_breaks(harness25):
    h = open_game(harness25)
    g = h.game
    assert g.prepare(CYAN, "C-RS1", None, CYAN).startswith("ignored")
    assert h.station("C-RS1").state == "IDLE"
    g.prepare(CYAN, "C-BS", BSInstruction("OUTPUT", "BASE_RED"), CYAN)
    h.run(5.25)
    assert h.station("C-BS").state == "READY-AT-OUTPUT" and h.station("C-BS").lights == READY
    assert g.prepare(CYAN, "C-BS", BSInstruction("OUTPUT", "BASE_RED"), CYAN) == "broken"
    assert h.world.workpiece_at("C-BS", "output") is None                # slots cleared


def test_prepared_blinks_green_until_fed(harness25):
    h = open_game(harness25)
    g = h.game
    color = g.rs_colors("C-RS1")[0]
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
