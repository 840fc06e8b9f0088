"""Fusing rotation sightings (2025: 8 rotations of 45 degrees): a weak glimpse
of a value is no evidence against it, so a far-off first sighting cannot undo
later close looks (seed 1's C-DS and seeds 2/3's C-SS in the 2025 benchmark
never reached the reporting confidence because of it)."""
import pytest

from rll_bt import rules
from teamserver.exploration.report import Reporter
from teamserver.exploration.symmetry import consistent_set
from teamserver.knowledge import model as M
from teamserver.knowledge.fusion import DiscreteBelief
from teamserver.knowledge.kb import KnowledgeBase

P25 = rules.profile("rcll2025")


def test_a_glimpse_below_one_in_k_is_no_evidence_at_all():
    b = DiscreteBelief(8)
    b.add("R1", 270, 0.01, t=0.0)
    assert b.probability(270) == pytest.approx(1 / 8)
    b.add("R2", 270, 0.76, t=0.0)
    assert b.probability(270) == pytest.approx(0.76)


def test_the_benchmark_case_weak_glimpse_between_two_looks_reaches_the_report_confidence():
    # seed 1: R1 looked at C-DS (0.57), R3 glimpsed it from afar (0.01), R3 came back (0.76)
    b = DiscreteBelief(8)
    b.add("R1", 270, 0.57, t=11.1)
    b.add("R3", 270, 0.01, t=35.2)
    b.add("R3", 270, 0.76, t=69.0)
    assert b.estimate().value == 270
    assert b.estimate().confidence >= 0.9


def test_disagreement_still_lowers_the_confidence():
    b = DiscreteBelief(8)
    b.add("R1", 90, 0.9)
    alone = b.probability(90)
    b.add("R2", 270, 0.8)
    assert b.probability(90) < alone
    assert b.sources(0.85) == {"R1"} and b.sources() == {"R1", "R2"}


def test_zero_confidence_glimpses_do_not_block_a_2025_rotation_report():
    # seed 2's C-SS: two glimpses at about 0, one at 0.09, then one close look at 0.92
    kb = KnowledgeBase(P25)
    z = P25.zone_number("C_Z55")
    for robot, conf, t in (("R1", 0.001, 1.7), ("R3", 0.001, 3.7), ("R3", 0.09, 23.7),
                           ("R2", 0.92, 45.0)):
        kb.add_observation(M.Observation("C-SS", M.ZONE, z, max(conf, 0.95), robot, t))
        kb.add_observation(M.Observation("C-SS", M.ORIENTATION, 135, conf, robot, t))
    cs = consistent_set(P25, kb.machines)
    g = cs.machines["C-SS"]
    assert (g.zone, g.orientation) == (z, 135) and g.orientation_confidence >= 0.9
    new = Reporter(P25, "C").new_values(cs, {}, 100.0, lambda code: None)
    assert new["C-SS"] == {"zone": z, "rotation": 135}
