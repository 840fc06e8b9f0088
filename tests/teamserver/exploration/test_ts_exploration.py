"""Exploration: Algorithm 1 branch by branch, and the baseline strategies."""
import pytest

from rll_bt import rules
from teamserver.exploration.strategies import (
    Algorithm1,
    Algorithm1Paper,
    NearestStrategy,
    OracleStrategy,
    RandomStrategy,
    make_strategy,
)
from teamserver.exploration.view import ExplorationView, opposite_zone
from teamserver.knowledge import model as M
from teamserver.knowledge.kb import KnowledgeBase

P16 = rules.profile("rcll2016")
CYAN_ZONES = list(range(1, 13))


def view(kb, zones=CYAN_ZONES, busy=()):
    return ExplorationView.from_kb(kb, "CYAN", zones, set(busy))


def observe(kb, machine, zone, zconf=0.95, light=None, lconf=0.95, robot="R1"):
    kb.add_observation(M.Observation(machine, M.ZONE, zone, zconf, robot))
    if light:
        kb.add_observation(M.Observation(machine, M.LIGHT, light, lconf, robot))


def test_opposite_zone_is_top_left_for_the_right_start_box_and_top_right_for_the_left():
    assert opposite_zone(P16, "CYAN", CYAN_ZONES) == 4            # x in [0,2], top row
    assert opposite_zone(P16, "MAGENTA", list(range(13, 25))) == 16
    p25 = rules.profile("rcll2025")
    z = opposite_zone(p25, "CYAN", p25.machine_zones("CYAN"))
    assert p25.zone_name(z) == "C_Z18"


def test_line_3_no_observations_sends_the_first_robot_to_the_opposite_zone():
    kb = KnowledgeBase(P16)
    d = Algorithm1(seed=1).next_zone(view(kb))
    assert (d.zone, d.branch) == (4, "opposite")


def test_line_5_opposite_zone_taken_or_visited_gives_a_random_unvisited_zone():
    kb = KnowledgeBase(P16)
    kb.mark_visited(4, 0.0)
    kb.mark_visited(1, 0.0)
    picks = {Algorithm1(seed=s).next_zone(view(kb, busy={7})).zone for s in range(30)}
    assert picks <= set(CYAN_ZONES) - {1, 4, 7}
    assert len(picks) > 3                                   # random, not a fixed order
    d1 = Algorithm1(seed=5).next_zone(view(kb))
    d2 = Algorithm1(seed=5).next_zone(view(kb))
    assert d1 == d2 and d1.branch == "random-start"        # seeded: reproducible


def test_line_11_unvisited_observed_zone_with_the_lowest_confidence_first():
    kb = KnowledgeBase(P16)
    observe(kb, "C-RS1", 6, zconf=0.9)
    observe(kb, "C-CS1", 10, zconf=0.5)
    observe(kb, "C-CS2", 2, zconf=0.7)
    kb.mark_visited(10, 0.0)
    d = Algorithm1().next_zone(view(kb))
    assert d.branch == "observed-unvisited"
    assert d.zone == 2                                      # 10 is visited; 2 is weaker than 6
    d = Algorithm1().next_zone(view(kb, busy={2}))
    assert d.zone == 2        # 2016: a type is read up close, so robots converge on observed zones


def test_line_15_too_few_machines_found_explores_a_random_unvisited_zone():
    kb = KnowledgeBase(P16)
    observe(kb, "C-RS1", 6, light=("GREEN",))
    kb.mark_visited(6, 0.0)
    v = view(kb)
    assert v.m_found(0.9) < v.n_mps
    d = Algorithm1(seed=3).next_zone(v)
    assert d.branch == "random-fallback" and d.zone in set(CYAN_ZONES) - {6}


#: a field where every station of ours is found, and the light codes they show
PLACEMENT = {"C-BS": 9, "C-DS": 4, "C-RS1": 6, "C-RS2": 19, "C-CS1": 22, "C-CS2": 2}
CODES = {"BS": ("GREEN",), "DS": ("YELLOW",), "RS1": ("RED",), "RS2": ("GREEN", "RED"),
         "CS1": ("GREEN", "YELLOW"), "CS2": ("RED", "YELLOW")}

def test_line_19_all_found_revisits_the_lowest_confidence_zone():
    kb = KnowledgeBase(P16)
    placement, codes = PLACEMENT, CODES
    for name, z in placement.items():
        observe(kb, name, z, zconf=0.97, light=codes[name[2:]], lconf=0.99 if name != "C-CS2"
                else 0.95)
        observe(kb, name, z, zconf=0.97, light=codes[name[2:]], robot="R2")
    for z in placement.values():
        kb.mark_visited(z, 0.0)
    zones = sorted(placement.values())
    v = view(kb, zones=zones)
    assert v.m_found(0.9) == v.n_mps == 6
    d = Algorithm1().next_zone(v)
    assert d.branch == "lowest-confidence"
    hyp = v.hypotheses()
    assert hyp[d.zone] == min(hyp.values())


# -- Algorithm 1 exactly as printed ---------------------------------------------------

def test_paper_lines_1_to_6_opposite_zone_then_a_seeded_random_unvisited_one():
    kb = KnowledgeBase(P16)
    assert Algorithm1Paper(seed=1).next_zone(view(kb)) == make_strategy("algorithm1-paper").next_zone(view(kb))
    d = Algorithm1Paper(seed=1).next_zone(view(kb))
    assert (d.zone, d.branch) == (4, "opposite")
    kb.mark_visited(4, 0.0)
    picks = {Algorithm1Paper(seed=s).next_zone(view(kb)).zone for s in range(30)}
    assert picks <= set(CYAN_ZONES) - {4} and len(picks) > 3
    assert Algorithm1Paper(seed=5).next_zone(view(kb)) == Algorithm1Paper(seed=5).next_zone(view(kb))


def test_paper_line_9_takes_every_unvisited_observed_zone_even_one_a_robot_is_heading_for():
    kb = KnowledgeBase(P16)
    observe(kb, "C-RS1", 6, zconf=0.99, light=("RED",), lconf=0.99)   # identified from afar
    observe(kb, "C-RS1", 6, zconf=0.99, light=("RED",), lconf=0.99, robot="R2")
    observe(kb, "C-CS1", 10, zconf=0.5)
    kb.mark_visited(10, 0.0)
    d = Algorithm1Paper().next_zone(view(kb, busy={6}))
    # the paper visits 6 (observed, not visited) although a robot heads there and it is known
    assert (d.zone, d.branch) == (6, "observed-unvisited")


def test_paper_line_14_too_few_found_searches_at_random_then_line_18_lowest_confidence():
    kb = KnowledgeBase(P16)
    observe(kb, "C-RS1", 6, light=("GREEN",))
    kb.mark_visited(6, 0.0)
    d = Algorithm1Paper(seed=3).next_zone(view(kb))
    assert d.branch == "random-fallback" and d.zone in set(CYAN_ZONES) - {6}
    for z in CYAN_ZONES:                         # nothing unvisited: line 15 cannot search
        kb.mark_visited(z, 0.0)
    d = Algorithm1Paper(seed=3).next_zone(view(kb))
    assert d.branch == "lowest-confidence" and d.zone in view(kb).hypotheses()


def test_twin_observation_counts_for_our_machine():
    kb = KnowledgeBase(P16)
    observe(kb, "M-RS2", 19, zconf=0.9)          # magenta's RS2 in Z19: ours is in Z7
    hyp = view(kb).hypotheses()
    assert 7 in hyp


def test_baselines_and_oracle():
    kb = KnowledgeBase(P16)
    kb.mark_visited(1, 0.0)
    assert RandomStrategy(seed=2).next_zone(view(kb)).zone in set(CYAN_ZONES) - {1}
    near = NearestStrategy().next_zone(view(kb), pose=(5.0, 5.9, 0.0))
    assert near.zone == 12                                   # x [4,6], y [4.5,6]
    truth = {"C-RS1": 6, "C-CS1": 11, "M-RS1": 18}
    o = OracleStrategy(truth).next_zone(view(kb), pose=(5.0, 5.9, 0.0))
    assert o.zone == 11 and o.branch == "oracle"
    with pytest.raises(ValueError, match="true machine zones"):
        make_strategy("oracle")
    with pytest.raises(ValueError, match="unknown exploration strategy"):
        make_strategy("greedy")


def test_a_light_the_gate_holds_back_leaves_its_zone_weak_and_it_is_explored_again():
    # rendered perception, seed 1: C-DS read sure from one view only; the fused belief said known,
    # the gate (two sure views) would not report it, and no robot went back
    from teamserver.exploration.lights import LightGate
    kb = KnowledgeBase(P16)
    placement, codes = PLACEMENT, CODES
    for name, z in placement.items():
        observe(kb, name, z, zconf=0.97)
        observe(kb, name, z, zconf=0.97, robot="R2")
        for n in ((1,) if name == "C-DS" else (1, 2)):
            kb.add_observation(M.Observation(name, M.LIGHT, codes[name[2:]], 0.995, M.view_source("R1", n)))
        kb.mark_visited(z, 0.0)
    zones = sorted(placement.values())
    gate = LightGate(kb)
    assert view(kb, zones=zones).hypotheses()[4] > 0.9                       # the fused belief: known
    gated = ExplorationView.from_kb(kb, "CYAN", zones, set(), lights=gate)
    assert gated.hypotheses()[4] == 0.0 and gated.m_found(0.9) == 5
    assert Algorithm1().next_zone(gated).zone == 4                           # read again
    kb.add_observation(M.Observation("M-DS", M.LIGHT, ("YELLOW",), 0.993, M.view_source("R2", 1)))
    assert ExplorationView.from_kb(kb, "CYAN", zones, set(), lights=gate).m_found(0.9) == 6   # the twin's view
