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


def test_a_2025_cap_station_by_a_wall_is_not_placed_by_its_twin():
    """From 2017 on a magenta RS or CS whose cyan twin stands by a wall gets a fixed rotation,
    not the mirrored one: its twin's pose says nothing of its own, so the map keeps the zone's
    centre and the known rotation."""
    link = AgentLink(KnowledgeBase(rules.profile("rcll2025")), Clock())
    prof = link.profile
    cyan_zone = prof.zone_number("C_Z18")  # y = 8: the magenta twin gets 180 whatever
    mx, my = prof.zone_centre(prof.mirror_zone(cyan_zone))
    link.kb.add_observation(M.Observation("M-CS1", M.POSE, (mx, my, math.radians(180)), 0.9, "R1", 50.0))
    link.kb.add_observation(M.Observation("C-CS1", M.ZONE, cyan_zone, 0.9, "R1", 50.0))
    m = entry(link.machine_map_msg(None), "C-CS1")
    assert (m.pose.x, m.pose.y) == pytest.approx(prof.zone_centre(cyan_zone))
    assert m.pose.theta == pytest.approx(0.0)
    assert not prof.twin_mirrors("C-CS1", cyan_zone) and prof.twin_mirrors("C-CS1", prof.zone_number("C_Z33"))
