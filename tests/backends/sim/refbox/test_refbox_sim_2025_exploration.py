"""2025 exploration inside PRODUCTION: zone and rotation reports, their scoring and lights,
reports without a name (MachineTypeFeedback), and the ground truth after the exploration time."""
from __future__ import annotations

from backends.sim.refbox import BSInstruction, ReportEntry
from backends.sim.refbox.messages import Messages, enum_name
from rll_bt.rules import CYAN, MAGENTA, mirror_machine_name

M25 = Messages("rcll2025")
YELLOW = {"RED": "OFF", "YELLOW": "ON", "GREEN": "OFF"}
YELLOW_BLINK = {"RED": "OFF", "YELLOW": "BLINK", "GREEN": "OFF"}
RED_YELLOW = {"RED": "ON", "YELLOW": "ON", "GREEN": "OFF"}
RED_YELLOW_BLINK = {"RED": "ON", "YELLOW": "BLINK", "GREEN": "OFF"}
GREEN = {"RED": "OFF", "YELLOW": "OFF", "GREEN": "ON"}
OFF = {"RED": "OFF", "YELLOW": "OFF", "GREEN": "OFF"}


def truth(g, m):
    return g.layout[m].zone, g.layout[m].rotation_deg


def entry(g, m, zone=True, rotation=True):
    """A report of ``m``: True for the right value, None to leave it out, else the value."""
    z, r = truth(g, m)
    return ReportEntry(m, None, z if zone is True else zone, r if rotation is True else rotation)


def wrong_zone(g, m):
    return next(z for z in g.profile.machine_zones(CYAN) if z != g.layout[m].zone)


def machine(mi, name):
    return next(m for m in mi.machines if m.name == name)


def test_zone_and_rotation_right_score_1_each_and_show_the_state(harness25):
    h = harness25().production()
    g = h.game
    assert g.exploring and g.phase == "PRODUCTION"
    assert g.machine_report(CYAN, [entry(g, "C-BS")], CYAN) == 2
    assert [(e.points, e.phase) for e in h.awards(CYAN)] == [(1, "PRODUCTION"), (1, "PRODUCTION")]
    assert g.exploration.correctly_reported(CYAN, "C-BS")
    assert h.station("C-BS").lights == GREEN and h.world.lights("C-BS") == GREEN   # IDLE
    assert g.points(CYAN) == 2
    assert g.prepare(CYAN, "C-BS", BSInstruction("OUTPUT", "BASE_RED"), CYAN) == "prepared"


def test_wrong_zone_costs_1_and_only_the_first_zone_counts(harness25):
    h = harness25().production()
    g = h.game
    assert g.machine_report(CYAN, [entry(g, "C-DS", zone=wrong_zone(g, "C-DS"))], CYAN) == -1
    assert h.station("C-DS").lights == RED_YELLOW
    assert g.machine_report(CYAN, [entry(g, "C-DS")], CYAN) == 0          # too late, ignored
    assert h.award_sum(CYAN) == -1 and g.points(CYAN) == 0                # floored per phase
    assert not g.exploration.correctly_reported(CYAN, "C-DS")
    assert g.exploration.state(CYAN, "C-DS").correct is False


def test_rotation_counts_only_once_the_zone_is_right_and_only_the_first(harness25):
    h = harness25().production()
    g = h.game
    m = "C-RS1"
    z, r = truth(g, m)
    assert g.machine_report(CYAN, [ReportEntry(m, None, None, r)], CYAN) == 0   # no zone yet
    assert g.exploration.state(CYAN, m).rotation is None
    assert h.station(m).lights == YELLOW
    assert g.machine_report(CYAN, [ReportEntry(m, None, z, None)], CYAN) == 1
    assert h.station(m).lights == YELLOW_BLINK
    assert g.machine_report(CYAN, [ReportEntry(m, None, None, (r + 90) % 360)], CYAN) == -1
    assert h.station(m).lights == RED_YELLOW_BLINK
    assert g.machine_report(CYAN, [ReportEntry(m, None, z, r)], CYAN) == 0
    assert not g.exploration.correctly_reported(CYAN, m)
    # after a wrong zone a rotation is ignored, right or wrong
    m2 = "C-CS2"
    assert g.machine_report(CYAN, [entry(g, m2, zone=wrong_zone(g, m2))], CYAN) == -1
    assert g.machine_report(CYAN, [entry(g, m2, zone=None)], CYAN) == 0


def test_other_teams_machines_and_unknown_names_are_ignored(harness25):
    h = harness25().production()
    g = h.game
    assert g.machine_report(CYAN, [entry(g, "M-BS"), ReportEntry("C-XX", None, 11, 0)], CYAN) == 0
    assert g.exploration.reported(CYAN) == [] and not h.awards(CYAN)
    assert g.machine_report(MAGENTA, [entry(g, "M-BS")], MAGENTA) == 2


def test_report_team_colour_must_match_its_channel(harness25):
    h = harness25().production()
    g = h.game
    assert g.machine_report(CYAN, [entry(g, "C-BS")], MAGENTA) == 0
    assert g.exploration.reported(CYAN) == [] and not h.awards(CYAN)
    assert any("Invalid report for team CYAN of team MAGENTA" in t for t in h.attention(MAGENTA))


def test_lights_yellow_until_reported_off_while_paused(harness25):
    h = harness25().production()
    g = h.game
    assert {st.lights["YELLOW"] for st in g.stations.values()} == {"ON"}
    g.set_state("PAUSED")
    assert all(st.lights == OFF for st in g.stations.values())
    g.set_state("RUNNING")
    assert h.station("M-SS").lights == YELLOW


def test_type_report_without_name_reveals_the_name_or_costs_1(harness25):
    h = harness25(seed=4).production()
    g = h.game
    rs_zone = g.layout.zone("C-RS1")
    assert g.machine_report(CYAN, [ReportEntry(None, "RS", rs_zone, None)], CYAN) == 0
    bad = next(z for z in g.profile.machine_zones(CYAN) if g.layout.machine_in_zone(z) is None)
    assert g.machine_report(CYAN, [ReportEntry(None, "BS", bad, None)], CYAN) == -1
    assert g.machine_report(CYAN, [ReportEntry(None, "BS", bad, None)], CYAN) == 0   # again
    other = next(z for z in g.profile.machine_zones(CYAN)
                 if g.layout.machine_in_zone(z) is None and z != bad)
    assert g.machine_report(CYAN, [ReportEntry(None, "BS", other, None)], CYAN) == 0  # one BS only
    mri = M25.machine_report_info(g, CYAN)
    fb = [(f.type, f.zone, f.name if f.HasField("name") else None,
           enum_name(f, "team_color")) for f in mri.reported_types]
    assert fb == [("RS", rs_zone, "C-RS1", "CYAN"), ("BS", bad, None, None)]
    assert list(mri.reported_machines) == []         # a type report names no machine


def test_type_report_finds_a_swapped_station_of_the_other_team(harness25):
    h = harness25(seed=4).production()
    g = h.game
    t = g.layout.swapped[0]                          # the M- station stands in cyan's half
    zone = g.layout.zone(f"M-{t}")
    assert g.profile.zone_team(zone) == CYAN
    g.machine_report(CYAN, [ReportEntry(None, t[:2], zone, None)], CYAN)
    f = M25.machine_report_info(g, CYAN).reported_types[0]
    assert (f.name, enum_name(f, "team_color")) == (f"M-{t}", "MAGENTA")


def test_machine_info_carries_zone_and_rotation_only_of_correctly_reported_machines(harness25):
    h = harness25().production()
    g = h.game
    g.machine_report(CYAN, [entry(g, "C-BS"), entry(g, "C-DS", rotation=None)], CYAN)
    mi = M25.machine_info(g, CYAN)
    bs, ds, cs = machine(mi, "C-BS"), machine(mi, "C-DS"), machine(mi, "C-CS1")
    assert (bs.zone, bs.rotation) == truth(g, "C-BS") and bs.correctly_reported
    assert enum_name(bs, "exploration_rotation_state") == "CORRECT_REPORT"
    assert not ds.HasField("zone") and not ds.HasField("rotation")    # rotation still open
    assert enum_name(ds, "exploration_zone_state") == "CORRECT_REPORT"
    assert enum_name(ds, "exploration_rotation_state") == "NO_REPORT"
    assert not cs.HasField("zone") and not cs.HasField("correctly_reported")


def test_ground_truth_released_after_the_exploration_time(harness25):
    h = harness25().production()
    g = h.game
    g.machine_report(CYAN, [entry(g, "C-DS", zone=wrong_zone(g, "C-DS"))], CYAN)
    assert g.prepare(CYAN, "C-CS1", None, CYAN) == "ignored: C-CS1 is not yet correctly reported"
    h.run(179.75)
    assert g.exploring and not g.exploration.released
    h.run(0.25)
    assert not g.exploring and g.exploration.released
    assert [e.game_time for e in h.events("report") if e.data.get("what") == "ground-truth"] == [180]
    for team in (CYAN, MAGENTA):
        for m in M25.machine_info(g, team).machines:
            assert (m.zone, m.rotation) == truth(g, m.name) and m.correctly_reported
    assert all(st.lights == GREEN for st in g.stations.values())       # IDLE everywhere
    assert g.machine_report(CYAN, [entry(g, "C-BS")], CYAN) == 0       # too late to score
    assert g.prepare(CYAN, "C-BS", BSInstruction("INPUT", "BASE_RED"), CYAN) == "prepared"
    assert h.award_sum(CYAN) == -1


def test_exploration_time_is_configurable_and_zero_releases_at_once(harness25):
    h = harness25(exploration=30).production()
    h.run(30)
    assert h.game.exploration.released
    h0 = harness25(exploration=0).production()
    assert h0.game.exploration.released and not h0.game.exploring
    assert h0.station("C-BS").lights == GREEN


def test_mirror_twins_are_reported_independently(harness25):
    h = harness25().production()
    g = h.game
    g.machine_report(MAGENTA, [entry(g, mirror_machine_name("C-SS"))], MAGENTA)
    assert g.exploration.correctly_reported(MAGENTA, "M-SS")
    assert not g.exploration.correctly_reported(CYAN, "C-SS")
    assert h.station("C-SS").lights == YELLOW and h.station("M-SS").lights == GREEN
