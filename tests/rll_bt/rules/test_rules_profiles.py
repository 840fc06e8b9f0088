import math
import random

import pytest

from rll_bt import rules


@pytest.fixture(params=rules.PROFILES)
def prof(request):
    return rules.profile(request.param)


def test_default_is_2016():
    assert rules.profile().name == "rcll2016"
    with pytest.raises(ValueError, match="rcll2016"):
        rules.profile("rcll1999")


def test_2016_zone_grid_matches_rulebook():
    p = rules.profile("rcll2016")
    # Zn: column (n-1)//4 -> x in [2c, 2c+2]; row (n-1)%4 -> y in [1.5r, 1.5r+1.5]
    for n in range(1, 13):
        c, r = (n - 1) // 4, (n - 1) % 4
        cx, cy = 2 * c + 1.0, 1.5 * r + 0.75
        assert p.zone_centre(n) == (cx, cy)
        assert p.zone_at(cx, cy) == n
        assert p.zone_centre(n + 12) == (-cx, cy)
        assert p.zone_at(-cx, cy) == n + 12
        assert p.zone_team(n) == rules.CYAN and p.zone_team(n + 12) == rules.MAGENTA
        assert p.mirror_zone(n) == n + 12
    assert p.zone_at(0.5, 6.5) is None
    assert p.zone_name(16) == "Z16" and p.zone_number("Z16") == 16
    assert p.fixed_zones == {"C-BS": 9, "C-DS": 4, "M-BS": 21, "M-DS": 16}
    # fixed zones are mirrored pairs
    assert p.mirror_zone(9) == 21 and p.mirror_zone(4) == 16


def test_2025_pose_to_zone_like_the_refbox():
    p = rules.profile("rcll2025")
    # x >= 0: C_Z(floor(x)+1)(floor(y)+1); x < 0: M_Z(floor(-x)+1)(floor(y)+1)
    assert p.zone_at(0.0, 0.0) == 11
    assert p.zone_at(2.3, 4.9) == 35
    assert p.zone_at(-2.3, 4.9) == 1035
    assert p.zone_name(1035) == "M_Z35" and p.zone_number("M_Z35") == 1035
    assert p.zone_number("C-Z23") == 23
    # centres: C_Zxy (x-0.5, y-0.5), M_Zxy (-(x-0.5), y-0.5)
    assert p.zone_centre(23) == (1.5, 2.5)
    assert p.zone_centre(1023) == (-1.5, 2.5)
    assert len(p.team_zones(rules.CYAN)) == 56
    # insertion zones are no machine zones
    for z in (51, 61, 71, 1051, 1061, 1071):
        assert z not in p.machine_zones(p.zone_team(z))


def test_2025_rotation_mirroring_and_wall_rule():
    p = rules.profile("rcll2025")
    table = {0: 180, 45: 135, 90: 90, 135: 45, 180: 0, 225: 315, 270: 270, 315: 225}
    for c, m in table.items():
        assert p.mirror_rotation(c) == m
        assert p.mirror_placement("C-BS", 33, c) == (1033, m)      # BS always mirrors
        assert p.mirror_placement("C-RS1", 33, c) == (1033, m)     # not next to a wall
    assert p.mirror_placement("C-RS1", 38, 90) == (1038, 180)      # y = 8
    assert p.mirror_placement("C-CS2", 21, 90) == (1021, 0)        # y = 1
    assert p.mirror_placement("C-CS2", 62, 90) == (1062, 0)        # insertion-adjacent
    assert p.mirror_placement("C-RS2", 74, 0) == (1074, 270)       # x = 7
    with pytest.raises(ValueError):
        p.mirror_placement("M-RS2", 1074, 0)


def test_tag_ids_and_parity(prof):
    seen = set()
    for m in prof.machines():
        i, o = prof.tag_ids(m)
        assert prof.machine_for_tag(i) == (m, "INPUT")
        assert prof.machine_for_tag(o) == (m, "OUTPUT")
        # ALVAR: input odd; ArUco: input even, output = input - 1
        if prof.tag_family == "alvar":
            assert i % 2 == 1 and o == i + 1
        else:
            assert i % 2 == 0 and o == i - 1
        seen |= {i, o}
    assert len(seen) == 2 * len(prof.machines())
    assert prof.machine_for_tag(999) is None


def test_machines_per_team():
    assert len(rules.profile("rcll2016").machines(rules.CYAN)) == 6
    p = rules.profile("rcll2025")
    assert sorted(p.machines(rules.MAGENTA)) == sorted(
        ["M-BS", "M-DS", "M-SS", "M-RS1", "M-RS2", "M-CS1", "M-CS2"])
    assert rules.machine_type("C-RS2") == "RS" and rules.mirror_machine_name("C-RS2") == "M-RS2"


def test_phases():
    p16, p25 = rules.profile("rcll2016").phases, rules.profile("rcll2025").phases
    assert (p16.setup, p16.exploration, p16.production, p16.overtime) == (300, 240, 900, 300)
    assert p16.exploration_deadline == 240
    assert (p25.exploration, p25.production, p25.exploration_in_production) == (0, 1200, 180)


def test_2016_light_codes_follow_formula_1():
    p = rules.profile("rcll2016")
    bit = {"GREEN": 1, "YELLOW": 2, "RED": 4}
    for code in range(1, 8):
        assert sum(bit[c] for c in p.light_code(code)) == code


@pytest.mark.parametrize("seed", range(20))
def test_ring_costs(prof, seed):
    rs, costs = prof.ring_setup(random.Random(seed))
    assert sorted(costs.values()) == [0, 0, 1, 2]
    assert sorted(rs["RS1"] + rs["RS2"]) == sorted(rules.RING_COLORS)
    if prof.name == "rcll2016":
        for colours in rs.values():      # each RS: one free and one costly colour
            assert sorted(costs[c] > 0 for c in colours) == [False, True]
    else:
        assert rs == {"RS1": ("RING_ORANGE", "RING_GREEN"), "RS2": ("RING_BLUE", "RING_YELLOW")}


def test_scoring_tables():
    s16 = rules.profile("rcll2016").scoring
    assert (s16.explore_type_ok, s16.explore_type_wrong, s16.explore_zone_ok, s16.explore_zone_wrong) == (5, -4, 3, -2)
    assert 6 * (s16.explore_type_ok + s16.explore_zone_ok) == 48
    assert s16.precap_by_complexity[1:] == (10, 30, 80)
    s25 = rules.profile("rcll2025").scoring
    assert s25.delivery_by_complexity == (20, 30, 50, 100)
    assert (s25.competitive_first, s25.competitive_second) == (10, -10)
    p = rules.profile("rcll2016")
    assert p.delivery_points(0, 100, 200) == 20
    assert p.delivery_points(0, 205.5, 200) == 12      # int(20 - 1.5 * 5)
    assert p.delivery_points(0, 210, 200) == 5
    assert p.delivery_points(0, 300, 200) == 5


def test_order_schedule_shape():
    o16 = rules.profile("rcll2016").orders
    assert len(o16) == 8 and o16[0].standing and o16[2].quantity == 2 and o16[7].overtime
    assert [o.complexities for o in o16[4:7]] == [(1,), (2,), (3,)]
    o25 = rules.profile("rcll2025").orders
    assert len(o25) == 11 and o25[0].standing and o25[1].standing and o25[10].competitive


def test_discretise_rotation(prof):
    assert prof.discretise_rotation(44.0) == 45
    assert prof.discretise_rotation(-10.0) == 0
    assert prof.discretise_rotation(359.0) == 0
    assert rules.theta_to_rotation(-math.pi / 2) == 270


def test_machine_times_are_the_real_machines():
    """refbox-rules.md: durations.h of the refbox's mock-up stations, measured on the MPS."""
    t = rules.MPS_TIMES
    assert (t.base_dispense, t.belt_to_middle, t.belt_to_output) == (1.1, 1.538, 2.656)
    assert (t.ring_mount, t.cap_operation, t.storage_operation) == (17.308, 17.5, 17.5)
    assert t.ring == pytest.approx(21.5, abs=0.01) and t.cap == pytest.approx(21.7, abs=0.01)
    assert t.base == pytest.approx(3.76, abs=0.01)
    assert [t.delivery(g) for g in (0, 1, 2, 3)] == [3.746, 3.746, 4.746, 3.983]
    for name in ("rcll2016", "rcll2025"):
        assert rules.profile(name).machine_times is rules.MPS_TIMES


def test_2025_late_delivery_deduction_by_quarters_of_the_window():
    """orders.clp: ceil(4 * late / L) / 4 of 75 % of the delivery points, at most 75 %."""
    p = rules.profile("rcll2025")
    begin, end = 820, 1000                                   # L = 180 s
    assert [p.delivery_points(3, end + late, end, begin) for late in
            (0, 1, 45, 46, 90, 91, 135, 136, 180, 500)] == [100, 82, 82, 63, 63, 44, 44, 25, 25, 25]
    assert p.delivery_points(0, end + 10, end, begin) == 20 - int(0.1875 * 20)


def test_production_rules_of_each_profile():
    p16, p25 = rules.profile("rcll2016"), rules.profile("rcll2025")
    assert p16.unprepared_input_breaks and not p25.unprepared_input_breaks
    assert p16.stuck_timeout is None and p25.stuck_timeout == 20.0
    assert p25.rs_paid_at_prepare and p25.wait_idle_after_delivery and p25.scoring.break_revokes
    assert (p25.scoring.ss_store, p25.scoring.ss_retrieve) == (-5, -5)
    assert (p16.down_start, p25.down_start) == (1.0, 180.0)
    assert sorted((b, c) for _, _, b, c in p25.prestored) == sorted(
        (b, c) for b in rules.BASE_COLORS for c in rules.CAP_COLORS)
    assert p25.referee_penalties == {"dropped-workpiece": -10, "obstruction": -20,
                                     "prepare-without-workpiece": -1}
    assert p16.referee_penalties == {"obstruction": -20} and not p16.prestored
