"""The real referee's machine rules (refbox-rules.md), one scenario per rule, both profiles:
the real machines' times, the cap shelf, 2016's input to a station not prepared, 2025's
20 s rule, its deductions when a machine breaks, prepare without instruction, WAIT-IDLE,
and the referee calls and BROKEN counts a game report shows."""
from __future__ import annotations

import pytest

from backends.sim.refbox import (
    BSInstruction,
    CSInstruction,
    DSInstruction,
    RSInstruction,
    Workpiece,
)
from rll_bt.rules import CYAN, MAGENTA, MPS_TIMES

T = MPS_TIMES


def open_2025(harness25, **kw):
    return harness25(exploration=0, **kw).production()


def free_color(g, rs="C-RS1"):
    return next(c for c in g.rs_colors(rs) if g.ring_costs[c] == 0)


def costly(g, cost):
    """(RS, colour) of the colour costing ``cost`` bases."""
    for rs in ("C-RS1", "C-RS2"):
        for c in g.rs_colors(rs):
            if g.ring_costs[c] == cost:
                return rs, c
    raise AssertionError(cost)


def state_times(h, machine):
    return [(e.data["state"], round(e.game_time, 3)) for e in h.events("machine")
            if e.machine == machine]


# -- both rule sets: the real machines' times ---------------------------------------------

@pytest.mark.parametrize("rules", ["rcll2016", "rcll2025"])
def test_machine_times_are_the_real_machines(harness, rules):
    """durations.h: a ring 21.5 s from the input to the output, a cap 21.7 s, a base 3.8 s,
    a delivery the gate's slot time."""
    h = harness(rules=rules, **({"exploration": 0} if rules == "rcll2025" else {})).production()
    g = h.game
    g.prepare(CYAN, "C-BS", BSInstruction("OUTPUT", "BASE_RED"), CYAN)
    g.prepare(CYAN, "C-RS1", RSInstruction(free_color(g)), CYAN)
    g.prepare(CYAN, "C-CS1", CSInstruction("RETRIEVE_CAP"), CYAN)
    h.world.put("C-RS1", "input", Workpiece("BASE_BLACK"))
    h.world.put("C-CS1", "input", h.world.take("C-CS1", "shelf0"))
    h.run(30)
    ready = {m: next(t for s, t in state_times(h, m) if s == "READY-AT-OUTPUT")
             for m in ("C-BS", "C-RS1", "C-CS1")}
    assert ready["C-BS"] == pytest.approx(T.base_dispense + T.belt_to_output)        # 3.76
    assert ready["C-RS1"] == pytest.approx(T.belt_to_middle + T.ring_mount + T.belt_to_output)
    assert ready["C-CS1"] == pytest.approx(T.belt_to_middle + T.cap_operation + T.belt_to_output)
    assert ready["C-RS1"] == pytest.approx(21.502) and ready["C-CS1"] == pytest.approx(21.694)


# -- both rule sets: the cap shelf -----------------------------------------------------------

@pytest.mark.parametrize("rules", ["rcll2016", "rcll2025"])
def test_cap_shelf_is_refilled_only_when_empty(harness, rules):
    h = harness(rules=rules).production()
    w = h.world
    shelf = ("shelf0", "shelf1", "shelf2")
    w.take("C-CS2", "shelf0")
    w.take("C-CS2", "shelf1")
    h.run(0.25)
    assert [w.workpiece_at("C-CS2", s) is None for s in shelf] == [True, True, False]
    w.take("C-CS2", "shelf2")
    h.run(0.25)
    assert all(w.workpiece_at("C-CS2", s).cap == "CAP_BLACK" for s in shelf)   # all three back


# -- 2016: a workpiece on a station that is not PREPARED breaks it ------------------------------

@pytest.mark.parametrize("machine", ["C-RS1", "C-CS2", "C-DS"])
def test_2016_a_workpiece_put_on_an_unprepared_station_breaks_it(harness, machine):
    """production.clp prod-machine-input-not-prepared: the machine is BROKEN for 30 s and the
    workpiece is lost; the DS before its PrepareMachine too."""
    h = harness().production()
    h.world.put(machine, "input", Workpiece("BASE_RED"))
    h.run(0.25)
    st = h.station(machine)
    assert st.state == "BROKEN" and st.broken_cause == "not-prepared"
    assert st.broken_reason == f"Input to {machine} while not prepared IDLE"
    assert h.world.workpiece_at(machine, "input") is None
    assert h.game.tally(CYAN).broken == {"not-prepared": 1}
    h.run(30)
    assert st.state == "IDLE"


def test_2016_input_while_waiting_idle_or_ready_breaks_too(harness):
    h = harness().production()
    g = h.game
    g.prepare(CYAN, "C-BS", BSInstruction("OUTPUT", "BASE_RED"), CYAN)
    h.run(4)
    base = h.world.take("C-BS", "output")
    h.run(0.25)
    assert h.station("C-BS").state == "WAIT-IDLE"
    h.world.put("C-BS", "input", base)
    h.run(0.25)
    assert h.station("C-BS").state == "BROKEN"
    assert "while not prepared WAIT-IDLE" in h.station("C-BS").broken_reason


def test_2016_a_prepared_station_takes_its_workpiece(harness):
    h = harness().production()
    g = h.game
    g.prepare(CYAN, "C-RS1", RSInstruction(free_color(g)), CYAN)
    h.world.put("C-RS1", "input", Workpiece("BASE_RED"))
    h.run(0.25)
    assert h.station("C-RS1").state == "PROCESSING" and not h.game.tally(CYAN).broken


def test_2016_input_while_down_is_judged_when_the_station_is_up(harness):
    h = harness().production()
    st = h.station("C-RS2")
    st.down = (1.0, 11.0)
    h.run(2)
    h.world.put("C-RS2", "input", Workpiece("BASE_RED"))
    h.run(2)
    assert st.state == "DOWN"
    h.run(8)
    assert st.state == "BROKEN" and st.broken_reason == "Input to C-RS2 while not prepared IDLE"


def test_2025_a_workpiece_on_an_unprepared_station_waits_for_the_prepare(harness25):
    """No such rule today: the workpiece lies on the input, a later prepare takes it."""
    h = open_2025(harness25)
    g = h.game
    h.world.put("C-RS1", "input", Workpiece("BASE_RED"))
    h.run(5)
    assert h.station("C-RS1").state == "IDLE"
    g.prepare(CYAN, "C-RS1", RSInstruction(free_color(g)), CYAN)
    h.run(22)
    assert h.station("C-RS1").state == "READY-AT-OUTPUT"


# -- 2025: 20 s in PREPARED, PROCESSING or PROCESSED without progress breaks ---------------

def test_2025_a_prepared_station_left_waiting_21_s_breaks(harness25):
    h = open_2025(harness25)
    g = h.game
    assert g.prepare(CYAN, "C-RS1", RSInstruction(free_color(g)), CYAN) == "prepared"
    h.run(19.75)
    assert h.station("C-RS1").state == "PREPARED"
    h.run(1.25)
    st = h.station("C-RS1")
    assert st.state == "BROKEN" and st.broken_cause == "timeout"
    assert st.broken_reason == "C-RS1: stuck in state PREPARED for > 20s"
    assert [e.game_time for e in h.events("machine") if e.data["state"] == "BROKEN"] == [20.0]
    tally = g.tally(CYAN)
    assert tally.broken == {"timeout": 1}
    assert tally.referee == {"prepare-without-workpiece": {"count": 1, "penalty": -1}}


@pytest.mark.parametrize("fed_at,broken", [(18.25, False), (18.5, True)])
def test_2025_the_workpiece_must_reach_the_middle_within_20_s_of_the_prepare(harness25, fed_at,
                                                                              broken):
    """The belt's 1.54 s to the middle count: fed 18.5 s after the prepare is too late."""
    h = open_2025(harness25)
    g = h.game
    g.prepare(CYAN, "C-RS1", RSInstruction(free_color(g)), CYAN)
    h.run(fed_at)
    h.world.put("C-RS1", "input", Workpiece("BASE_RED"))   # seen at game time fed_at
    h.run(30)
    assert (h.station("C-RS1").state == "BROKEN") == broken
    assert (h.world.workpiece_at("C-RS1", "output") is None) == broken


def test_2025_every_step_of_a_real_machine_stays_within_20_s(harness25):
    h = open_2025(harness25)
    g = h.game
    g.prepare(CYAN, "C-CS1", CSInstruction("RETRIEVE_CAP"), CYAN)
    h.world.put("C-CS1", "input", h.world.take("C-CS1", "shelf1"))
    h.run(25)
    assert h.station("C-CS1").state == "READY-AT-OUTPUT"
    assert [s for s, _ in state_times(h, "C-CS1")] == ["IDLE", "PREPARED", "PROCESSING",
                                                      "PROCESSED", "READY-AT-OUTPUT"]
    h.run(60)                             # READY-AT-OUTPUT has no timeout: a robot takes it
    assert h.station("C-CS1").state == "READY-AT-OUTPUT"


def test_2025_a_down_period_holds_the_20_s(harness25):
    h = open_2025(harness25)
    g = h.game
    rs, color = costly(g, 0)
    st = h.station(rs)
    st.down = (10.0, 50.0)
    g.prepare(CYAN, rs, RSInstruction(color), CYAN)
    h.run(45)
    assert st.state == "DOWN"
    h.run(10)                              # up at 50 with 10 s of its 20 s left
    assert st.state == "PREPARED"
    h.run(5.25)
    assert st.state == "BROKEN"


def test_2016_ready_or_prepared_stations_wait_forever(harness):
    h = harness().production()
    g = h.game
    g.prepare(CYAN, "C-DS", DSInstruction(1), CYAN)
    g.prepare(CYAN, "C-BS", BSInstruction("OUTPUT", "BASE_RED"), CYAN)
    h.run(300)
    assert h.station("C-DS").state == "PREPARED" and h.station("C-BS").state == "READY-AT-OUTPUT"


# -- 2025: an RS prepared without its bases, bases on a broken RS, deductions --------------

def test_2025_an_rs_prepared_without_its_additional_bases_breaks_at_once(harness25):
    h = open_2025(harness25)
    g = h.game
    rs, color = costly(g, 2)
    h.world.put(rs, "slide", Workpiece("BASE_RED"))
    h.run(0.25)
    assert g.prepare(CYAN, rs, RSInstruction(color), CYAN) == "broken"
    assert h.station(rs).broken_reason == f"{rs}: insufficient bases (1 < 2)"
    assert h.game.tally(CYAN).broken == {"insufficient-bases": 1}


def test_2025_a_broken_rs_with_bases_on_its_slide_takes_their_points_back(harness25):
    """production-mps-broken: -2 per unused base; bases fed while BROKEN are not counted."""
    h = open_2025(harness25)
    g = h.game
    for _ in range(2):
        h.world.put("C-RS1", "slide", Workpiece("BASE_RED"))
        h.run(0.25)
    assert h.award_sum(CYAN) == 4 and h.station("C-RS1").slide_loaded == 2
    g.reset_machine(CYAN, "C-RS1", CYAN)
    assert h.station("C-RS1").state == "BROKEN"
    assert [(e.points, e.reason) for e in h.awards(CYAN)][-1] == \
        (-4, "deducting unused additional bases at C-RS1")
    h.world.put("C-RS1", "slide", Workpiece("BASE_RED"))      # into the broken RS
    h.run(0.25)
    assert h.award_sum(CYAN) == 0 and h.station("C-RS1").slide_loaded == 2
    h.run(30)
    assert h.station("C-RS1").state == "IDLE" and h.station("C-RS1").slide_loaded == 0


def test_2016_a_broken_rs_keeps_the_points_of_its_bases(harness):
    h = harness().production()
    g = h.game
    h.world.put("C-RS1", "slide", Workpiece("BASE_RED"))
    h.run(0.25)
    g.reset_machine(CYAN, "C-RS1", CYAN)
    h.world.put("C-RS1", "slide", Workpiece("BASE_RED"))      # 2016 scores it even now
    h.run(0.25)
    assert h.award_sum(CYAN) == 4
    h.run(30)
    assert h.station("C-RS1").slide_loaded == 0


def test_2025_a_broken_cs_holding_a_retrieved_cap_takes_its_points_back(harness25):
    h = open_2025(harness25)
    g = h.game
    g.prepare(CYAN, "C-CS1", CSInstruction("RETRIEVE_CAP"), CYAN)
    h.world.put("C-CS1", "input", h.world.take("C-CS1", "shelf0"))
    h.run(25)
    assert h.station("C-CS1").cap_buffer and h.award_sum(CYAN) == 2
    g.reset_machine(CYAN, "C-CS1", CYAN)
    assert h.award_sum(CYAN) == 0
    assert h.awards(CYAN)[-1].reason == "deducting retrieved cap at C-CS1"
    assert g.tally(CYAN).broken == {"reset": 1}


# -- 2025: prepare without instruction, WAIT-IDLE after a delivery ---------------------------

@pytest.mark.parametrize("machine", ["C-BS", "C-RS1", "C-CS1", "C-DS", "C-SS"])
def test_2025_prepare_without_instruction_breaks(harness25, machine):
    h = open_2025(harness25)
    assert h.game.prepare(CYAN, machine, None, CYAN) == "broken"
    assert h.station(machine).broken_reason == f"Prepare received for {machine} without data"


def test_2025_a_delivery_is_followed_by_5_s_wait_idle(harness25):
    h = open_2025(harness25)
    g = h.game
    g.prepare(CYAN, "C-DS", DSInstruction(order_id=0), CYAN)
    h.world.put("C-DS", "input", Workpiece("BASE_RED"))
    h.run(10)
    states = state_times(h, "C-DS")
    assert [s for s, _ in states] == ["IDLE", "PREPARED", "PROCESSING", "PROCESSED",
                                      "WAIT-IDLE", "IDLE"]
    done = dict(states)
    assert done["IDLE"] - done["WAIT-IDLE"] == pytest.approx(5.0)   # the last IDLE
    assert done["PROCESSED"] == pytest.approx(T.delivery(1))       # order 0 uses slot 1


def test_2016_a_delivery_goes_straight_back_to_idle(harness):
    h = harness().production()
    g = h.game
    g.prepare(CYAN, "C-DS", DSInstruction(2), CYAN)
    h.world.put("C-DS", "input", Workpiece("BASE_RED"))
    h.run(5)
    assert [s for s, _ in state_times(h, "C-DS")] == ["IDLE", "PREPARED", "PROCESSING", "IDLE"]


# -- referee calls ---------------------------------------------------------------------

def test_referee_calls_for_a_drop_an_obstruction_and_a_prepare_never_fed(harness25):
    """What the refbox leaves to the referee is reported, never taken off the score."""
    h = open_2025(harness25)
    g = h.game
    h.world.drop(Workpiece("BASE_RED"), ("CYAN", 2))
    h.world.put("M-RS1", "slide", Workpiece("BASE_BLACK"), ("CYAN", 1))
    g.prepare(CYAN, "C-CS2", CSInstruction("RETRIEVE_CAP"), CYAN)
    h.run(25)
    assert g.tally(CYAN).referee == {
        "dropped-workpiece": {"count": 1, "penalty": -10},
        "obstruction": {"count": 1, "penalty": -20},
        "prepare-without-workpiece": {"count": 1, "penalty": -1}}
    assert g.tally(CYAN).referee_penalty == -31
    assert g.points(CYAN) == 0 and g.tally(MAGENTA).referee == {}
    texts = [e.text for e in h.events("referee")]
    assert "robot 2 of CYAN dropped BASE_RED on the floor (referee: -10)" in texts


def test_2016_referee_calls_carry_the_2016_penalties(harness):
    h = harness().production()
    g = h.game
    h.world.drop(Workpiece("BASE_RED"), ("MAGENTA", 1))
    h.world.put("C-RS2", "slide", Workpiece("BASE_BLACK"), ("MAGENTA", 3))
    g.prepare(MAGENTA, "M-DS", DSInstruction(1), MAGENTA)
    h.run(1)
    g.set_phase("POST_GAME")                      # still waiting at the end: reported then
    calls = g.tally(MAGENTA).referee
    assert calls["dropped-workpiece"] == {"count": 1, "penalty": 0}        # none in 2016
    assert calls["obstruction"] == {"count": 1, "penalty": -20}
    assert calls["prepare-without-workpiece"]["count"] == 1


def test_the_tally_crosses_the_snapshot_file_of_a_refbox_process(harness25, tmp_path):
    """rll-bt sim --processes reads the refbox's game from its snapshot file."""
    import json

    from backends.sim.refbox.view import GameView, SnapshotView, snapshot
    h = open_2025(harness25)
    h.world.put("M-DS", "input", Workpiece("BASE_RED"), ("CYAN", 1))
    h.game.prepare(CYAN, "C-RS1", RSInstruction(free_color(h.game)), CYAN)
    h.run(21)
    path = tmp_path / "refbox.json"
    path.write_text(json.dumps(snapshot(GameView(h.game))))
    back = SnapshotView(path).tally(CYAN)
    assert back == h.game.tally(CYAN) and back.broken == {"timeout": 1}
    assert back.referee["obstruction"] == {"count": 1, "penalty": -20}
