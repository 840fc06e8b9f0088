"""The symmetry sanity check and what gets reported."""
from rll_bt import rules
from teamserver.exploration.report import Reporter
from teamserver.exploration.symmetry import consistent_set
from teamserver.knowledge import model as M
from teamserver.knowledge.kb import KnowledgeBase

P16, P25 = rules.profile("rcll2016"), rules.profile("rcll2025")


def obs(kb, machine, prop, value, conf, robot="R1"):
    kb.add_observation(M.Observation(machine, prop, value, conf, robot))


def test_a_strong_twin_overrules_a_weak_observation_of_our_machine():
    kb = KnowledgeBase(P16)
    obs(kb, "C-RS1", M.ZONE, 3, 0.5)
    obs(kb, "M-RS1", M.ZONE, 20, 0.95, "R2")          # mirror of Z8
    obs(kb, "M-RS1", M.ZONE, 20, 0.9, "R3")
    cs = consistent_set(P16, kb.machines)
    assert cs.machines["C-RS1"].zone == 8
    assert cs.machines["M-RS1"].zone == 20
    assert "C-RS1" in cs.conflicts


def test_two_machines_in_one_zone_cannot_both_stay():
    kb = KnowledgeBase(P16)
    obs(kb, "C-CS1", M.ZONE, 6, 0.9)
    obs(kb, "C-CS1", M.ZONE, 7, 0.7, "R2")
    obs(kb, "C-RS2", M.ZONE, 6, 0.95)
    cs = consistent_set(P16, kb.machines)
    assert cs.machines["C-RS2"].zone == 6
    assert cs.machines["C-CS1"].zone == 7                # its second best


def test_exactly_one_ring_station_stands_in_the_other_half():
    kb = KnowledgeBase(P16)
    obs(kb, "C-RS1", M.ZONE, 2, 0.9)                    # both seen in our half ...
    obs(kb, "C-RS2", M.ZONE, 7, 0.6)
    obs(kb, "C-RS2", M.ZONE, 19, 0.5, "R2")             # ... but RS2 could be across
    cs = consistent_set(P16, kb.machines)
    assert cs.machines["C-RS1"].zone == 2
    assert cs.machines["C-RS2"].zone == 19
    assert P16.zone_team(19) == "MAGENTA"


def test_fixed_zones_and_unknowns():
    cs = consistent_set(P16, {})
    assert cs.machines["C-BS"].zone == 9 and cs.machines["M-DS"].zone == 16
    assert cs.machines["C-RS1"].zone is None


def test_twins_share_their_light_code():
    kb = KnowledgeBase(P16)
    obs(kb, "C-CS2", M.LIGHT, ("GREEN",), 0.6)
    obs(kb, "M-CS2", M.LIGHT, ("RED",), 0.55)
    obs(kb, "M-CS2", M.LIGHT, ("GREEN",), 0.7, "R2")
    cs = consistent_set(P16, kb.machines)
    assert cs.machines["C-CS2"].light == ("GREEN",) == cs.machines["M-CS2"].light


def test_2025_rotation_is_mirrored_and_wall_twins_get_the_fixed_rotation():
    kb = KnowledgeBase(P25)
    obs(kb, "C-BS", M.ZONE, 33, 0.95)
    obs(kb, "C-BS", M.ORIENTATION, 45, 0.6)
    obs(kb, "M-BS", M.ORIENTATION, 135, 0.8)           # mirror of 45
    obs(kb, "C-RS1", M.ZONE, 38, 0.95)                 # y = 8: a wall
    obs(kb, "C-RS1", M.ORIENTATION, 270, 0.9)
    cs = consistent_set(P25, kb.machines)
    assert cs.machines["C-BS"].orientation == 45 and cs.machines["M-BS"].orientation == 135
    assert cs.machines["M-RS1"].orientation == 180 and cs.machines["M-RS1"].zone == 1038
    assert cs.machines["C-RS1"].orientation == 270


def test_reports_confident_values_early_and_the_rest_only_if_they_pay():
    kb = KnowledgeBase(P16)
    obs(kb, "C-RS1", M.ZONE, 2, 0.97)
    obs(kb, "C-RS1", M.LIGHT, ("RED",), 0.97)
    obs(kb, "C-CS1", M.ZONE, 6, 0.5)                    # ~0.5 after the others: pays 5p-2>0
    rep = Reporter(P16, "C", thresh=0.9, margin=20)
    cs = consistent_set(P16, kb.machines)
    types = {("RED",): "T0000001"}.get
    early = rep.new_values(cs, {}, time_left=100, type_string=types)
    assert early["C-RS1"] == {"zone": 2, "type": "T0000001"}
    assert "C-CS1" not in early
    assert early["C-BS"] == {"zone": 9}                 # fixed by the rules
    late = rep.new_values(cs, early, time_left=10, type_string=types)
    assert late.get("C-CS1", {}).get("zone") == 6
    assert "C-RS1" not in late                          # sent values are frozen
    entries = Reporter.entries({"C-RS1": early["C-RS1"]})
    assert entries == [{"name": "C-RS1", "zone": 2, "type": "T0000001"}]


def test_2025_reports_rotation_only_with_a_zone():
    kb = KnowledgeBase(P25)
    obs(kb, "C-CS2", M.ORIENTATION, 90, 0.99)
    rep = Reporter(P25, "C", thresh=0.9)
    cs = consistent_set(P25, kb.machines)
    assert "C-CS2" not in rep.new_values(cs, {}, 100, lambda _line: None)
    obs(kb, "C-CS2", M.ZONE, 44, 0.99)
    cs = consistent_set(P25, kb.machines)
    assert rep.new_values(cs, {}, 100, lambda _line: None)["C-CS2"] == {"zone": 44, "rotation": 90}
