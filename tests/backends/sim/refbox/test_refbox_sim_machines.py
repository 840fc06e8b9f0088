"""The simulated refbox drives MQTT machines as the real refbox does: a real
broker, the PyBullet world's stations on it (backends.sim.mps, the machines'
side), and the refbox's game over :class:`MachineWorld` (the refbox's side),
which sees the stations only through the broker.  Every station type goes
through its steps: the world's workpieces change as the refbox's game says,
a robot's put and take (here the test's hand in the world) reach the game
as the machines' sensors report them, a slide base is counted, the lights
follow the game."""
from __future__ import annotations

import time

import pytest

from backends.sim.mps import Broker, MqttMachines
from backends.sim.refbox import BSInstruction, CSInstruction, DSInstruction, RefboxGame, RSInstruction, Timing
from backends.sim.refbox.machines import MachineWorld, machine_config
from rll_bt.clock import WallClock
from rll_bt.rules import profile
from tests.support.mps_world import FAST, RunningWorld, wait_for


@pytest.fixture(scope="module")
def rig():
    broker = Broker("amqtt")
    running = RunningWorld(seed=5, rate=4.0).start()
    served = MqttMachines(running.hall, broker.host, broker.port).start(timeout=60.0)
    world = MachineWorld(running.world.layout, broker.host, broker.port)
    game = RefboxGame("rcll2025", WallClock(), world, seed=5, team_cyan="Caro",
                      timing=Timing.from_profile(profile("rcll2025"), setup=1.0, exploration=0.0),
                      config=machine_config(FAST))
    world.attach(game)
    game.start()
    game.set_phase("PRODUCTION")             # no exploration time: every station counts as reported
    yield running, world, game
    world.close()
    served.stop()
    running.stop()
    broker.stop()


def run_until(world, game, pred, timeout=20.0, what="condition"):
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        world.pump()
        game.tick()
        if pred():
            return
        time.sleep(0.01)
    raise AssertionError(f"timed out waiting for {what} (states: "
                         f"{ {n: s.state for n, s in game.stations.items() if n.startswith('C-')} }; "
                         f"{[e.text for e in game.events if e.kind in ('attention', 'machine')][-6:]})")


def state(game, machine):
    return game.stations[machine].state


def in_world(running, fn):
    return running.call(lambda: fn(running.world))


def test_the_lights_follow_the_game(rig):
    running, world, game = rig
    run_until(world, game, lambda: in_world(running, lambda w: w.lights("C-DS"))["GREEN"] == "ON",
              what="C-DS green (IDLE in production)")
    assert ("C-DS", "LIGHT GREEN ON") in world.sent


def test_base_dispensed_and_taken(rig):
    running, world, game = rig
    game.prepare("CYAN", "C-BS", BSInstruction("OUTPUT", "BASE_SILVER"))
    run_until(world, game, lambda: state(game, "C-BS") == "READY-AT-OUTPUT", what="BS ready")
    wp = wait_for(lambda: in_world(running, lambda w: w.workpiece_at("C-BS", "output")), what="the base")
    assert wp.base == "BASE_SILVER"
    in_world(running, lambda w: w.remove_workpiece("C-BS", "output"))       # a robot takes it
    run_until(world, game, lambda: state(game, "C-BS") in ("WAIT-IDLE", "IDLE"), what="BS taken")


def test_ring_mounted_with_slide_bases_counted(rig):
    running, world, game = rig
    colour = next(c for c in game.rs_colors("C-RS1") if game.ring_cost(c) >= 1)
    points = game.points("CYAN")
    for _ in range(game.ring_cost(colour)):
        in_world(running, lambda w: w.spawn_workpiece("C-RS1", "slide", "BASE_RED"))
    run_until(world, game, lambda: game.stations["C-RS1"].slide_loaded == game.ring_cost(colour),
              what="slide bases counted")
    assert game.points("CYAN") > points                                         # additional bases score
    game.prepare("CYAN", "C-RS1", RSInstruction(colour))
    in_world(running, lambda w: w.spawn_workpiece("C-RS1", "input", "BASE_BLACK"))   # a robot puts it
    run_until(world, game, lambda: state(game, "C-RS1") == "READY-AT-OUTPUT", what="RS ready")
    wp = wait_for(lambda: in_world(running, lambda w: w.workpiece_at("C-RS1", "output")), what="the product")
    assert wp.rings == (colour,) and wp.base == "BASE_BLACK"
    feeder = game.rs_colors("C-RS1").index(colour) + 1
    assert ("C-RS1", f"MOUNT_RING RING{feeder}") in world.sent
    in_world(running, lambda w: w.remove_workpiece("C-RS1", "output"))
    run_until(world, game, lambda: state(game, "C-RS1") in ("WAIT-IDLE", "IDLE"), what="RS taken")


def test_cap_retrieved_mounted_and_delivered(rig):
    running, world, game = rig
    game.prepare("CYAN", "C-CS1", CSInstruction("RETRIEVE_CAP"))
    in_world(running, lambda w: w.spawn_workpiece("C-CS1", "input", "BASE_RED", cap="CAP_GREY"))
    run_until(world, game, lambda: state(game, "C-CS1") == "READY-AT-OUTPUT", what="cap retrieved")
    assert game.stations["C-CS1"].cap_buffer == "CAP_GREY"
    assert wait_for(lambda: in_world(running, lambda w: w.workpiece_at("C-CS1", "output"))).cap is None
    in_world(running, lambda w: w.remove_workpiece("C-CS1", "output"))
    run_until(world, game, lambda: state(game, "C-CS1") == "IDLE", timeout=30, what="CS idle")
    # the base comes from the BS: the refbox knows it by the barcode its BS gave it
    game.prepare("CYAN", "C-BS", BSInstruction("OUTPUT", "BASE_BLACK"))
    run_until(world, game, lambda: state(game, "C-BS") == "READY-AT-OUTPUT", what="BS ready")
    base = wait_for(lambda: in_world(running, lambda w: w.remove_workpiece("C-BS", "output")), what="base")
    game.prepare("CYAN", "C-CS1", CSInstruction("MOUNT_CAP"))
    in_world(running, lambda w: w.store.put(base, "C-CS1", "input"))
    run_until(world, game, lambda: state(game, "C-CS1") == "READY-AT-OUTPUT", what="cap mounted")
    product = in_world(running, lambda w: w.remove_workpiece("C-CS1", "output"))
    assert product.cap == "CAP_GREY"
    # the refbox knows what the workpiece became by its barcode when it reaches the DS
    game.prepare("CYAN", "C-DS", DSInstruction(order_id=0))
    # order 0's window is open: PREPARED and at once PROCESSING, waiting for the workpiece
    run_until(world, game, lambda: state(game, "C-DS") in ("PREPARED", "PROCESSING"), what="DS prepared")
    in_world(running, lambda w: w.store.put(product, "C-DS", "input"))      # the same workpiece, its barcode
    run_until(world, game, lambda: any(e.kind == "delivery" for e in game.events), what="delivered")
    delivery = next(e for e in game.events if e.kind == "delivery")
    assert "BASE_BLACK+CAP_GREY" in delivery.text, delivery.text    # judged as what the refbox made of it
    wait_for(lambda: running.hall["C-DS"].delivered, what="the world's DS delivering")
    assert in_world(running, lambda w: w.workpiece_at("C-DS", "input")) is None
