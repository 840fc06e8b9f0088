"""The machine map the team server sends its robots: a machine of the other team whose pose no
robot has seen stands where the field's mirror puts its twin, off its zone's centre alike."""
import math

import pytest

from rll_bt import rules
from teamserver.knowledge import model as M
from teamserver.knowledge.kb import KnowledgeBase
from teamserver.links.agents import AgentLink


class Clock:
    def now(self) -> float:
        return 100.0


def entry(mm, name):
    return next(m for m in mm.machines if m.name == name)


@pytest.fixture
def link():
    return AgentLink(KnowledgeBase(rules.profile("rcll2016")), Clock())


def test_an_unseen_machine_stands_at_the_mirror_of_its_seen_twin(link):
    kb = link.kb
    # C-RS1 seen 0.39 m off zone 24's centre (by the wall), at 45 degrees
    kb.add_observation(M.Observation("C-RS1", M.POSE, (-4.63, 5.12, 0.787), 0.9, "R1", 50.0))
    kb.add_observation(M.Observation("M-RS1", M.ZONE, 12, 0.9, "R1", 50.0))
    m = entry(link.machine_map_msg(None), "M-RS1")
    assert (m.pose.x, m.pose.y) == pytest.approx((4.63, 5.12))
    assert m.pose.theta == pytest.approx(math.pi - 0.787)
    assert m.zone == 12


def test_without_its_twin_seen_an_unseen_machine_stands_at_its_zone_centre(link):
    link.kb.add_observation(M.Observation("M-RS1", M.ZONE, 12, 0.9, "R1", 50.0))
    m = entry(link.machine_map_msg(None), "M-RS1")
    assert (m.pose.x, m.pose.y) == pytest.approx(link.profile.zone_centre(12))


def test_a_twin_whose_mirror_falls_in_another_zone_is_not_used(link):
    kb = link.kb
    kb.add_observation(M.Observation("C-RS1", M.POSE, (-4.63, 5.12, 0.787), 0.9, "R1", 50.0))
    kb.add_observation(M.Observation("M-RS1", M.ZONE, 2, 0.9, "R1", 50.0))
    m = entry(link.machine_map_msg(None), "M-RS1")
    assert (m.pose.x, m.pose.y) == pytest.approx(link.profile.zone_centre(2))
