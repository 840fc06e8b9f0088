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
