"""The simulated refbox's clock follows a simulation's SimTimeSync, as the
real refbox's ``time-sync`` does: game time advances by the differences of
the synced time (faster or slower than its own clock), stands still while
the simulation is paused, and no first sync makes it jump; the controller
stream also carries every machine's zone and rotation (the real refbox's
restricted MachineInfo), from SETUP on."""
from __future__ import annotations

import pytest

from backends.sim.mps.timesync import TimeSync
from backends.sim.refbox import RefboxGame, Timing
from backends.sim.refbox.node import RefboxNode
from rll_bt import msgs
from rll_bt.clock import SimClock, SyncedClock
from rll_bt.comm import Bus, MessageRegistry
from rll_bt.rules import profile

MS = msgs.message_set("rcll2025")
REG = MessageRegistry.from_message_set(MS)


@pytest.fixture
def rig():
    wall = SimClock()                              # the refbox's own clock (its machine's)
    clock = SyncedClock(wall)
    game = RefboxGame("rcll2025", clock, seed=4, team_cyan="Caro",
                      timing=Timing.from_profile(profile("rcll2025"), setup=300))
    bus = Bus(wall)
    node = RefboxNode.on_bus(game, bus, keys={"Caro": "k"})
    ctrl = bus.stream_client("refbox", registry=REG, name="world")
    sync = TimeSync(profile="rcll2025", period=0.1, real_time_factor=None, transport=ctrl)
    return wall, game, node, ctrl, sync


def _run(wall, node, sync, wall_s, sim_rate, sim, dt=0.1, paused=False):
    """``wall_s`` of the refbox's clock while the simulation runs ``sim_rate`` times as fast."""
    for _ in range(int(round(wall_s / dt))):
        wall.advance(dt)
        if not paused:
            sim[0] += dt * sim_rate
        sync.fixed_rtf = 0.0 if paused else sim_rate
        sync.update(sim[0], paused=paused)
        node.step()
    return sim[0]


def test_game_time_follows_the_simulation_paused_and_fast(rig):
    wall, game, node, ctrl, sync = rig
    sim = [1000.0]                                  # the simulation's clock is far ahead: no jump
    _run(wall, node, sync, 1.0, 1.0, sim)
    game.start()
    t0 = game.game_time
    _run(wall, node, sync, 5.0, 1.0, sim)
    assert game.phase == "SETUP" and game.game_time - t0 == pytest.approx(5.0, abs=0.25)
    t1 = game.game_time
    _run(wall, node, sync, 4.0, 0.0, sim, paused=True)
    assert game.game_time == pytest.approx(t1, abs=0.15)            # the simulation paused: so is the game
    _run(wall, node, sync, 4.0, 3.0, sim)
    assert game.game_time - t1 == pytest.approx(12.0, abs=0.5)      # 3x: 12 game s in 4 s of its own clock
    assert node.received["SimTimeSync"] > 80 and not node.ignored["SimTimeSync"]


def test_the_controller_stream_knows_where_every_machine_stands(rig):
    wall, game, node, ctrl, sync = rig
    game.start()                                    # SETUP: nothing reported yet
    _run(wall, node, sync, 1.0, 1.0, [0.0])
    infos = [r.msg for r in ctrl.receive() if r.type_name.endswith("MachineInfo")]
    assert infos
    got = {m.name: (m.zone, m.rotation) for m in infos[-1].machines}
    assert got == {n: (pl.zone, pl.rotation_deg % 360) for n, pl in game.layout.machines.items()}
