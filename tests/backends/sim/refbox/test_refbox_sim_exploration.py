"""2016 exploration: MachineReport scoring, first-value rule, lights, phase gating."""
from __future__ import annotations

from backends.sim.refbox import ReportEntry
from rll_bt.rules import CYAN, MAGENTA


def _truth(game, machine):
    return game.exploration.expected_type(machine), game.layout.machines[machine].zone


def _other_type(game, machine):
    right = game.exploration.expected_type(machine)
    return next(t for t in game.exploration.type_of_code.values() if t != right)


def _wrong_zone(game, machine):
    return next(z for z in range(1, 13) if z != game.layout.machines[machine].zone)


def test_correct_type_and_zone_score_and_blink_green(harness):
    h = harness().exploration()
    g = h.game
    t, z = _truth(g, "C-RS1")
    assert g.machine_report(CYAN, [ReportEntry("C-RS1", t, z)], channel_team=CYAN) == 5 + 3
    assert h.station("C-RS1").lights == {"RED": "OFF", "YELLOW": "OFF", "GREEN": "BLINK"}
    assert g.world.lights("C-RS1")["GREEN"] == "BLINK"
    h.run(5.5)                                         # feedback ends: the light code again
    assert h.station("C-RS1").lights == g.exploration.machine_lights("C-RS1")
    assert g.points(CYAN) == 8


def test_wrong_type_and_wrong_zone_penalties_and_red_blink(harness):
    h = harness().exploration()
    g = h.game
    assert g.machine_report(CYAN, [ReportEntry("C-CS1", _other_type(g, "C-CS1"))], CYAN) == -4
    assert h.station("C-CS1").lights["RED"] == "BLINK"
    assert g.machine_report(CYAN, [ReportEntry("C-DS", zone=_wrong_zone(g, "C-DS"))], CYAN) == -2
    t, _z = _truth(g, "C-BS")
    assert g.machine_report(CYAN, [ReportEntry("C-BS", t, _wrong_zone(g, "C-BS"))], CYAN) == 5 - 2
    assert h.award_sum(CYAN, "EXPLORATION") == -4 - 2 + 3
    assert h.station("C-BS").lights["RED"] == "BLINK"


def test_only_the_first_value_per_machine_counts(harness):
    h = harness().exploration()
    g = h.game
    t, z = _truth(g, "C-RS2")
    assert g.machine_report(CYAN, [ReportEntry("C-RS2", _other_type(g, "C-RS2"))], CYAN) == -4
    # a later correct type changes nothing; the zone is still open and counts once
    assert g.machine_report(CYAN, [ReportEntry("C-RS2", t, z)], CYAN) == 3
    assert g.machine_report(CYAN, [ReportEntry("C-RS2", t, z)], CYAN) == 0
    assert g.machine_report(CYAN, [ReportEntry("C-RS2", t, _wrong_zone(g, "C-RS2"))], CYAN) == 0
    assert h.award_sum(CYAN) == -1
    assert g.exploration.reported(CYAN) == ["C-RS2"]


def test_report_for_the_other_teams_machine_scores_nothing_in_2016(harness):
    """The 2016 refbox defines -6 for it, but only commented-out rules use it."""
    h = harness().exploration()
    g = h.game
    t, z = _truth(g, "M-BS")
    assert g.machine_report(CYAN, [ReportEntry("M-BS", t, z)], CYAN) == 0
    assert g.machine_report(CYAN, [ReportEntry("M-BS", "WRONG", 3)], CYAN) == 0
    assert g.ledger.entries == [] and not h.events("report")
    assert g.exploration.state(MAGENTA, "M-BS") is None
    # the real report of M-BS by its own team still counts in full afterwards
    assert g.machine_report(MAGENTA, [ReportEntry("M-BS", t, z)], MAGENTA) == 8


def test_unknown_names_are_ignored(harness):
    h = harness().exploration()
    assert h.game.machine_report(CYAN, [ReportEntry("C-XX", "ABC", 3)], CYAN) == 0
    assert h.game.ledger.entries == []


def test_reports_outside_exploration_and_on_the_wrong_channel_are_dropped(harness):
    h = harness()
    g = h.game
    t, z = _truth(g, "C-BS")
    g.start()                                          # SETUP
    assert g.machine_report(CYAN, [ReportEntry("C-BS", t, z)], CYAN) == 0
    g.set_phase("EXPLORATION")
    assert g.machine_report(CYAN, [ReportEntry("C-BS", t, z)], channel_team=MAGENTA) == 0
    assert any("Invalid report" in a for a in h.attention(MAGENTA))
    g.set_phase("PRODUCTION")
    assert g.machine_report(CYAN, [ReportEntry("C-BS", t, z)], CYAN) == 0
    assert g.ledger.entries == []


def test_exploration_points_floored_at_zero_per_phase(harness):
    h = harness().exploration()
    g = h.game
    for m in ("C-BS", "C-DS", "C-CS1"):
        g.machine_report(CYAN, [ReportEntry(m, _other_type(g, m), _wrong_zone(g, m))], CYAN)
    assert h.award_sum(CYAN, "EXPLORATION") == -18
    assert g.points(CYAN) == 0                        # floored, not negative
    g.set_phase("PRODUCTION")
    g.award(CYAN, 20, "test delivery")
    assert g.points(CYAN) == 20                       # exploration debt does not eat production
    assert g.points_by_phase(CYAN) == {"EXPLORATION": -18, "PRODUCTION": 20}


def test_machine_lights_follow_pause_in_exploration(harness):
    h = harness().exploration()
    g = h.game
    code = g.exploration.machine_lights("M-CS2")
    assert h.station("M-CS2").lights == code
    g.set_state("PAUSED")
    assert h.station("M-CS2").lights == {"RED": "OFF", "YELLOW": "OFF", "GREEN": "OFF"}
    g.set_state("RUNNING")
    assert h.station("M-CS2").lights == code
