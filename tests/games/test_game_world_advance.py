"""How a process game's world follows the wall clock (games.processes.world_advance): a sim-backend
game drops the wall time a late step could not cover; a hardware game, whose devices (the emulated
base's motors) run on the wall clock, steps all of it, so the world's robots move as far as their
odometry says."""
from games.hardware import HardwareGame
from games.processes import ProcessGame
from games.world_pace import world_advance


def walk(catch_up, ticks):
    """Wall times the loop ran at -> (world seconds stepped, the wall time the world stands at)."""
    last, stepped = ticks[0], 0.0
    for now in ticks[1:]:
        dt, last = world_advance(last, now, 0.1, catch_up)
        stepped += dt
    return stepped, last


def test_a_late_tick_drops_what_one_step_cannot_cover_without_catch_up():
    stepped, at = walk(None, [0.0, 0.05, 0.6, 0.65, 0.7])       # 0.55 s late once
    assert abs(stepped - 0.25) < 1e-9 and at == 0.7             # 0.45 s never stepped: the world is behind


def test_with_catch_up_the_world_steps_every_wall_second_in_steps_of_at_most_a_tenth():
    ticks = [0.0, 0.05, 0.6] + [0.6 + 0.01 * k for k in range(1, 11)]
    last, steps = ticks[0], []
    for now in ticks[1:]:
        dt, last = world_advance(last, now, 0.1, 2.0)
        steps.append(dt)
    assert max(steps) <= 0.1 + 1e-12
    assert abs(sum(steps) - ticks[-1]) < 1e-9 and abs(last - ticks[-1]) < 1e-9     # caught up: none dropped


def test_catch_up_drops_only_what_is_more_than_its_bound_behind():
    stepped, at = walk(2.0, [0.0, 5.0] + [5.0 + 0.001 * k for k in range(1, 40)])
    # of the 5 s gap 3 s are dropped, the 2 s of the bound and the wall time after it are stepped
    assert abs(stepped - 2.039) < 1e-9 and abs(at - 5.039) < 1e-9


def test_a_hardware_game_catches_up_and_a_sim_backend_game_does_not():
    assert HardwareGame.catch_up is not None and HardwareGame.catch_up >= 1.0
    assert ProcessGame.catch_up is None


def test_the_world_lag_counts_the_wall_time_the_world_stood_too_far_behind_to_cast():
    from games.world_pace import WorldLag
    lag = WorldLag(0.5)
    # (wall time of the tick, wall time the world stands at): on time, then 1.4 s behind, catching up in
    # tenths, on time again, and once more 0.7 s behind
    ticks = [(0.0, 0.0), (0.1, 0.1), (1.5, 0.2), (1.6, 0.3), (1.7, 0.4), (1.8, 0.5), (1.9, 0.6), (2.0, 1.9),
             (2.1, 2.1), (2.9, 2.2), (3.0, 3.0)]
    for now, at in ticks:
        lag.add(now, at)
    s = lag.summary()
    assert abs(s["longest_s"] - 1.3) < 1e-9
    assert s["stale_spells"] == 2
    # a stale tick counts the wall time since the tick before it: 1.5 .. 1.9 s (from 0.1 s) and 2.9 s (from 2.1 s)
    assert abs(lag.stale_seconds - (1.9 - 0.1 + 2.9 - 2.1)) < 1e-9


def test_a_hardware_game_reports_how_far_its_world_fell_behind():
    from games.report import table
    summary = {"profile": "rcll2016", "seed": 1, "robots": 1, "strategy": "algorithm1", "perception": "camera",
               "finished": True, "phase": "POST_GAME", "sim_time": 10.0, "phase_lengths": {"SETUP": 10.0},
               "setup_shortened": False, "points": {"total": 0, "exploration": 0, "production": 0},
               "exploration": {"points": 0, "max_points": 48, "wrong": 0, "all_points_after": None,
                               "sure_all_after": None},
               "orders_delivered": 0, "stations_broken": {"count": 0, "by_cause": {}}, "referee": {"calls": {}},
               "collisions": 0, "collisions_by_kind": {}, "robot_stats": {},
               "hardware_stats": {"CYAN/1": {"serial_polls_per_s": 180.0, "scans_per_s": 9.9, "frames_per_s": 4.6,
                                             "watchdog_motion_stops": 0}},
               "world_lag": {"longest_s": 1.3, "stale_s": 2.6, "stale_spells": 2, "stale_above_s": 0.5}}
    text = table(summary)
    assert "world behind the wall clock: at most 1.30 s" in text and "for 2.6 s in 2 spells" in text
