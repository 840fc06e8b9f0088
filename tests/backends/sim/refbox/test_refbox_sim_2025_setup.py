"""The 2025 refbox (rcll2025) before play: field, stations, tags, placement, phases, orders,
ring stations and down periods; every way these differ from the 2016 game."""
from __future__ import annotations

import pytest

from backends.sim.refbox import RefboxGame, Timing
from backends.sim.refbox.messages import Messages
from rll_bt.clock import SimClock
from rll_bt.rules import CYAN, MAGENTA, machine_type, mirror_machine_name, profile

P25 = profile("rcll2025")


def _game(seed=0, **phases):
    return RefboxGame("rcll2025", SimClock(), seed=seed, team_cyan="Caro", team_magenta="Grips",
                      timing=Timing.from_profile(P25, **phases) if phases else None)


def test_field_of_14_by_8_m_with_1_m_zones_and_stations_in_their_zones():
    g = _game(seed=3)
    f = g.profile.field
    assert (f.x_max - f.x_min, f.y_max - f.y_min) == (14.0, 8.0)
    for _m, pl in g.layout.machines.items():
        assert g.profile.zone_at(pl.pose.x, pl.pose.y) == pl.zone          # at the zone centre
        assert g.profile.zone_centre(pl.zone) == pytest.approx((pl.pose.x, pl.pose.y))
        b = g.profile.zones.bounds(pl.zone)
        assert (b.x_max - b.x_min, b.y_max - b.y_min) == (1.0, 1.0)
    assert g.profile.zone_name(g.layout.zone("C-BS"))[:3] in ("C_Z", "M_Z")


def test_seven_stations_per_team_with_the_storage_station_and_aruco_tags():
    g = _game()
    assert sorted(g.stations) == sorted(
        f"{t}-{k}" for t in "CM" for k in ("BS", "DS", "SS", "RS1", "RS2", "CS1", "CS2"))
    assert type(g.stations["C-SS"]).__name__ == "StorageStation"
    mi = Messages("rcll2025").machine_info(g, CYAN)
    tags = {m.name: (m.input_tag, m.output_tag) for m in mi.machines}
    assert tags["C-SS"] == (142, 141) and tags["C-CS1"] == (102, 101) and tags["C-DS"] == (132, 131)
    mi = Messages("rcll2025").machine_info(g, MAGENTA)
    tags = {m.name: (m.input_tag, m.output_tag) for m in mi.machines}
    assert tags["M-SS"] == (242, 241) and tags["M-RS2"] == (214, 213) and tags["M-BS"] == (222, 221)
    assert {m.type for m in mi.machines} == {"BS", "DS", "SS", "RS", "CS"}


@pytest.mark.parametrize("seed", range(8))
def test_placement_mirrors_rotation_with_the_wall_rule_and_swaps_one_rs_and_one_cs(seed):
    g = _game(seed=seed)
    lay, p = g.layout, g.profile
    zones = [pl.zone for pl in lay.machines.values()]
    assert len(set(zones)) == 14
    forbidden = {51, 61, 71, 52, 1051, 1061, 1071, 1052}          # insertion zones, entrance
    assert not forbidden & set(zones)
    swapped = []
    for t in p.machine_types:
        c, m = lay[f"C-{t}"], lay[f"M-{t}"]
        if p.zone_team(c.zone) == CYAN:
            assert p.zone_team(m.zone) == MAGENTA
            assert p.mirror_placement(c.machine, c.zone, c.rotation_deg) == (m.zone, m.rotation_deg)
            continue
        # swapped: zone and rotation traded, the cyan station stands where the twin stood
        assert p.zone_team(m.zone) == CYAN
        assert p.mirror_placement(c.machine, m.zone, m.rotation_deg) == (c.zone, c.rotation_deg)
        swapped.append(t)
    assert sorted(machine_type("C-" + t) for t in swapped) == ["CS", "RS"]
    assert tuple(swapped) == tuple(t for t in p.machine_types if t in lay.swapped)


def test_the_wall_rule_fixes_the_rotation_of_a_wall_side_rs_or_cs_twin():
    """Over some seeds, a cyan RS/CS at a wall gives its twin the fixed rotation, which
    differs from the plain mirror rotation in some of them."""
    p, seen = P25, set()
    for seed in range(40):
        lay = _game(seed=seed).layout
        for t in p.machine_types:
            if machine_type("C-" + t) not in ("RS", "CS") or t in lay.swapped:
                continue
            c, m = lay[f"C-{t}"], lay[f"M-{t}"]
            x, y = p.zones.digits(c.zone)
            fixed = 180 if y == 8 else 0 if (y == 1 or (y == 2 and x >= 5)) else \
                270 if x == 7 else None
            if fixed is not None:
                assert m.rotation_deg == fixed
                if fixed != p.mirror_rotation(c.rotation_deg):
                    seen.add(t)
            else:
                assert m.rotation_deg == p.mirror_rotation(c.rotation_deg)
    assert seen, "no seed put an RS/CS at a wall with a rotation the wall rule changes"


def test_timing_has_no_exploration_phase_but_180_s_of_exploring_in_production():
    t = Timing.from_profile(P25)
    assert (t.setup, t.exploration, t.production, t.overtime) == (300, 0, 1200, 300)
    assert t.exploration_time == 180 and t.production_scale == 1.0
    short = Timing.from_profile(P25, exploration=60, production=600)
    assert (short.exploration, short.exploration_time, short.production_scale) == (0, 60, 0.5)


def test_setup_then_production_never_exploration_then_overtime_on_a_tie(harness25):
    h = harness25(production=300, overtime=60)
    g = h.game
    g.start()
    assert g.phase == "SETUP"
    h.run(5)
    assert g.phase == "PRODUCTION" and g.game_time == 0
    h.run(300)
    assert g.overtime and g.phase == "PRODUCTION"                     # 0 : 0
    h.run(60)
    assert g.phase == "POST_GAME" and g.state == "PAUSED"
    assert [e.text for e in h.events("phase") if not e.data.get("final")] == [
        "phase PRE_GAME -> SETUP", "phase SETUP -> PRODUCTION", "overtime: tied at 0",
        "phase PRODUCTION -> POST_GAME"]
    with pytest.raises(ValueError, match="no EXPLORATION phase"):
        g.set_phase("EXPLORATION")


def test_training_game_without_teams_starts_in_production():
    g = RefboxGame("rcll2025", SimClock(), seed=1)
    g.start()
    assert g.phase == "PRODUCTION" and g.exploring


@pytest.mark.parametrize("seed", range(5))
def test_eleven_orders_standing_competitive_overtime_and_none_before_exploration_time(seed):
    g = _game(seed=seed)
    o = {x.id: x for x in g.orders}
    assert sorted(o) == list(range(1, 12))
    assert o[1].standing and o[1].complexity in (0, 1) and (o[1].begin, o[1].end) == (0, 1200)
    assert o[2].standing and o[2].complexity in (2, 3) and o[2].activate_at == 0
    assert o[11].overtime and o[11].complexity == 0 and o[11].competitive
    assert (o[11].begin, o[11].end, o[11].activate_at) == (1200, 1500, 1200)
    competitive = [i for i in range(3, 11) if o[i].competitive]
    assert len(competitive) == 1 and not (o[1].competitive or o[2].competitive)
    for i in range(3, 11):
        assert 180 <= o[i].activate_at <= o[i].begin < o[i].end <= 1200
        rings = o[i].rings
        assert len(rings) == o[i].complexity and all(a != b for a, b in zip(rings, rings[1:]))
        assert 1 <= o[i].gate <= 3 and o[i].quantity == 1


def test_orders_activate_only_after_the_exploration_time(harness25):
    h = harness25(seed=2).production()
    g = h.game
    assert [o.id for o in g.active_orders()] == [1, 2]
    h.run(179.75)
    assert [o.id for o in g.active_orders()] == [1, 2]
    first = min(o.activate_at for o in g.orders if o.id > 2)
    h.run(first - 179.75 + 0.25)
    assert len(g.active_orders()) > 2 and 11 not in [o.id for o in g.active_orders()]
    oi = Messages("rcll2025").order_info(g)
    assert {o.id: o.competitive for o in oi.orders} == \
        {o.id: o.competitive for o in g.active_orders()}


def test_fixed_ring_station_colours_with_random_costs():
    costs = set()
    for seed in range(12):
        g = _game(seed=seed)
        assert g.rs_colors("C-RS1") == g.rs_colors("M-RS1") == ("RING_ORANGE", "RING_GREEN")
        assert g.rs_colors("C-RS2") == g.rs_colors("M-RS2") == ("RING_BLUE", "RING_YELLOW")
        assert sorted(g.ring_costs.values()) == [0, 0, 1, 2]
        costs.add(tuple(sorted(g.ring_costs.items())))
    assert len(costs) > 3                                   # the costs change between games
    ri = Messages("rcll2025").ring_info(g)
    assert len(ri.rings) == 4 and sorted(r.raw_material for r in ri.rings) == [0, 0, 1, 2]


@pytest.mark.parametrize("seed", range(10))
def test_down_periods_30_to_60_s_start_only_after_exploration(seed):
    g = _game(seed=seed)
    down = {m: st.down for m, st in g.stations.items() if st.down}
    assert sorted(machine_type(m) for m in down) == ["CS", "CS", "RS", "RS"]
    for m, (start, end) in down.items():
        assert start >= 180 and 30 <= end - start <= 60 and end <= 1200
        assert down[mirror_machine_name(m)] == (start, end)
    scaled = _game(seed=seed, production=600, exploration=60)
    for st in scaled.stations.values():
        if st.down:
            assert st.down[0] >= 60 and 15 <= st.down[1] - st.down[0] <= 30
