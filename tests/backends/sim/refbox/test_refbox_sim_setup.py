"""Game set-up and flow: seeds, placement, light codes, orders, phases and time."""
from __future__ import annotations

import pytest

from backends.sim.refbox import parse_phase_lengths
from backends.sim.refbox.orders2016 import TIMES_2016
from rll_bt.rules import CYAN, MAGENTA, machine_team, mirror_machine_name, profile

P16 = profile("rcll2016")


def _fingerprint(game):
    return (
        {m: (p.zone, p.rotation_deg, p.pose.x, p.pose.y) for m, p in game.layout.machines.items()},
        dict(game.exploration.code_of_pair), dict(game.exploration.type_of_code),
        [str(o) for o in game.orders], dict(game.ring_costs), dict(game._rs_colors),
        {m: s.down for m, s in game.stations.items()},
    )


def test_same_seed_same_game_and_other_seed_differs(harness):
    a, b, c = harness(seed=11).game, harness(seed=11).game, harness(seed=12).game
    assert _fingerprint(a) == _fingerprint(b)
    fa, fc = _fingerprint(a), _fingerprint(c)
    assert fa[0] != fc[0] and fa[3] != fc[3] and fa[2] != fc[2]


@pytest.mark.parametrize("seed", range(8))
def test_placement_fixed_zones_mirroring_and_one_rs_cs_swap(harness, seed):
    game = harness(seed=seed).game
    zones = {m: p.zone for m, p in game.layout.machines.items()}
    assert zones["C-BS"] == 9 and zones["C-DS"] == 4
    assert zones["M-BS"] == 21 and zones["M-DS"] == 16
    assert len(set(zones.values())) == 12
    swapped = [m for m, z in zones.items() if P16.zone_team(z) != machine_team(m)]
    # exactly one RS pair and one CS pair stand in the other half
    assert sorted(m[2:4] for m in swapped if m.startswith("C-")) == ["CS", "RS"]
    for m, z in zones.items():
        twin = mirror_machine_name(m)
        assert zones[twin] == P16.mirror_zone(z)          # twins mirror (swapped or not)
        rot, trot = game.layout.machines[m].rotation_deg, game.layout.machines[twin].rotation_deg
        if m in swapped or twin in swapped:
            continue
        if m.startswith("C-"):
            assert trot == P16.mirror_rotation(rot)


def test_light_codes_shared_by_twins_distinct_per_pair_and_type_strings(harness):
    game = harness(seed=3).game
    ex = game.exploration
    codes = [ex.code_of(f"C-{t}") for t in P16.machine_types]
    assert len(set(codes)) == 6 and set(codes) <= set(P16.light_codes)
    for t in P16.machine_types:
        assert ex.code_of(f"C-{t}") == ex.code_of(f"M-{t}")
        assert ex.expected_type(f"C-{t}") == ex.expected_type(f"M-{t}")
    types = list(ex.type_of_code.values())
    assert len(set(types)) == 6 and all(len(s) == 8 and s.isalnum() for s in types)
    # the code lights are the profile's steady pattern
    for m in ("C-BS", "M-CS2"):
        on = {c for c, s in ex.machine_lights(m).items() if s == "ON"}
        assert on == set(P16.light_code(ex.code_of(m)))


def test_exploration_zone_lists_exchange_the_swapped_zones(harness):
    game = harness(seed=5).game
    lists = game.exploration.zone_lists()
    assert len(lists[CYAN]) == len(lists[MAGENTA]) == 12
    assert sorted(lists[CYAN] + lists[MAGENTA]) == list(range(1, 25))
    for m, p in game.layout.machines.items():        # every machine is in its team's list
        assert p.zone in lists[machine_team(m)]
    moved = [z for z in lists[CYAN] if z > 12]
    assert len(moved) == 2                            # the swapped RS and CS zones


def test_order_schedule_shapes_and_windows(harness):
    h = harness(seed=9)
    orders = h.game.orders
    assert [o.id for o in orders] == list(range(1, 9))
    assert [o.complexity for o in orders] == [0, 0, 0, 0, 1, 2, 3, 0]
    assert orders[2].quantity == 2 and all(o.quantity == 1 for i, o in enumerate(orders) if i != 2)
    assert (orders[0].begin, orders[0].end, orders[0].activate_at) == (0, 900, 0)
    assert (orders[7].begin, orders[7].end, orders[7].activate_at) == (900, 1200, 900)
    for o in orders[1:7]:
        (slo, shi), (dlo, dhi), (llo, lhi) = TIMES_2016[o.id]
        assert dlo <= o.end - o.begin <= dhi
        assert o.end <= 900 and (slo <= o.begin <= shi or o.end == 900)
        assert o.activate_at == max(0, o.begin - (o.begin - o.activate_at))
        assert 0 <= o.activate_at <= o.begin
        assert len(set(o.rings)) == o.complexity and 1 <= o.gate <= 3
        assert o.base.startswith("BASE_") and o.cap.startswith("CAP_")


def test_short_production_scales_order_windows(harness):
    h = harness(seed=9, production=90)
    for o in h.game.orders[:7]:
        assert 0 <= o.activate_at <= o.begin <= o.end <= 90


def test_ring_setup_costs_and_station_colours(harness):
    game = harness(seed=4).game
    assert sorted(game.ring_costs.values()) == [0, 0, 1, 2]
    rs1, rs2 = game.rs_colors("C-RS1"), game.rs_colors("C-RS2")
    assert rs1 == game.rs_colors("M-RS1") and len(set(rs1 + rs2)) == 4
    for colors in (rs1, rs2):                 # one free and one costly colour per RS
        assert sorted(game.ring_costs[c] > 0 for c in colors) == [False, True]


def test_down_periods_one_rs_one_cs_per_team_mirrored(harness):
    game = harness(seed=2).game
    down = {m: s.down for m, s in game.stations.items() if s.down}
    assert sorted(m[2:4] for m in down if m.startswith("C-")) == ["CS", "RS"]
    for m, period in down.items():
        assert down[mirror_machine_name(m)] == period
        start, end = period
        assert 30 <= end - start <= 120 and start >= 1 and end <= 900
        assert start == int(start) and end == int(end)


def test_phase_flow_timing_and_points_snapshot(harness):
    h = harness(setup=10, exploration=20, production=60, overtime=30)
    g = h.game
    assert (g.phase, g.state) == ("PRE_GAME", "WAIT_START")
    h.run(5)
    assert g.game_time == 0.0                     # nothing moves before the start
    g.start()
    assert (g.phase, g.state) == ("SETUP", "RUNNING")
    h.run(9.75)
    assert g.phase == "SETUP" and g.game_time == pytest.approx(9.75)
    h.run(0.5)
    assert g.phase == "EXPLORATION" and g.game_time == pytest.approx(0.25)   # restarts
    h.run(20)
    assert g.phase == "PRODUCTION"
    g.award(CYAN, 3, "test")                      # no tie: no overtime
    h.run(61)
    assert (g.phase, g.state) == ("POST_GAME", "PAUSED")
    phases = [e.text for e in h.events("phase")]
    assert phases[:4] == ["phase PRE_GAME -> SETUP", "phase SETUP -> EXPLORATION",
                          "phase EXPLORATION -> PRODUCTION", "phase PRODUCTION -> POST_GAME"]


def test_overtime_on_a_tie_then_post_game(harness):
    h = harness(setup=1, exploration=1, production=20, overtime=10)
    g = h.game
    g.start()
    h.run(2.5)
    assert g.phase == "PRODUCTION"
    h.run(21)
    assert g.phase == "PRODUCTION" and g.overtime and g.game_time > 20
    assert g.orders[7].active                     # the overtime order
    h.run(10)
    assert g.phase == "POST_GAME"


def test_pause_freezes_game_time(harness):
    h = harness()
    g = h.game
    g.start()
    h.run(2)
    g.set_state("PAUSED")
    h.run(50)
    assert g.phase == "SETUP" and g.game_time == pytest.approx(2.0)
    g.set_state("RUNNING")
    h.run(1)
    assert g.game_time == pytest.approx(3.0)


def test_speed_scales_game_time_not_robot_timeouts(harness):
    h = harness(speed=10.0)
    g = h.game
    g.start()
    g.beacon(number=1, team_name="Caro", peer_name="R1")
    h.run(2)
    assert g.phase == "EXPLORATION" and g.game_time == pytest.approx(15.0)   # 5 s setup + 15
    assert not g.robots.robots[(1, "Caro")].lost      # 2 clock seconds < 5 s
    h.run(4)
    assert g.robots.robots[(1, "Caro")].lost


def test_training_game_without_teams_starts_in_exploration(harness):
    h = harness(teams=(None, None))
    h.game.start()
    assert h.game.phase == "EXPLORATION"


def test_team_names_only_before_production(harness):
    h = harness(teams=(None, None))
    assert h.game.set_team("cyan", "Caro") and h.game.teams[CYAN] == "Caro"
    h.game.start()
    h.game.set_phase("PRODUCTION")
    assert not h.game.set_team("MAGENTA", "Late")
    assert h.game.teams[MAGENTA] is None and h.attention()


def test_robot_registry_keys_lost_and_back(harness):
    h = harness()
    g = h.game
    g.beacon(number=1, team_name="Caro", peer_name="R1", pose=(1.0, 2.0, 0.5))
    g.beacon(number=1, team_name="Grips", peer_name="G1")
    g.beacon(number=2, team_name="Nobody", peer_name="X")
    g.beacon(number=0, team_name="LLSF", peer_name="RefBox")   # another refbox: ignored
    assert set(g.robots.robots) == {(1, "Caro"), (1, "Grips"), (2, "Nobody")}
    assert [(r.team_color, r.number) for r in g.robots.listed()] == [(CYAN, 1), (MAGENTA, 1)]
    h.run(5.5)
    lost = [e for e in h.events("robot") if e.data["what"] == "lost"]
    assert len(lost) == 3
    g.beacon(number=1, team_name="Caro", peer_name="R1")
    assert [e.data["what"] for e in h.events("robot")][-1] == "back"


@pytest.mark.parametrize("text,expected", [
    ("setup=10,exploration=60,production=120", {"setup": 10, "exploration": 60, "production": 120}),
    (" overtime = 5 ", {"overtime": 5}),
    ("", {}),
])
def test_parse_phase_lengths(text, expected):
    assert parse_phase_lengths(text) == expected


@pytest.mark.parametrize("text", ["setup", "lunch=5", "setup=abc", "setup=-1", "setup=inf"])
def test_parse_phase_lengths_rejects(text):
    with pytest.raises(ValueError, match="bad phase length"):
        parse_phase_lengths(text)


def test_unsupported_profile_is_a_clear_error():
    from dataclasses import replace

    from backends.sim.refbox import RefboxGame
    from rll_bt.clock import SimClock
    with pytest.raises(ValueError, match="does not play 'rcll1999'"):
        RefboxGame(replace(profile("rcll2016"), name="rcll1999"), SimClock())
