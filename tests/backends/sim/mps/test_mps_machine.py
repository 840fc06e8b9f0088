"""One station machine on the world's clock, without a network: durations,
feedback order, and what a real machine does with a step it cannot do."""
from __future__ import annotations

import pytest

from backends.sim.mps import Command, Durations, MachineHall


@pytest.fixture(scope="module")
def world():
    from backends.sim import World
    w = World("rcll2025", seed=2)
    yield w
    w.close()


@pytest.fixture
def hall(world):
    for wp, loc in world.workpieces():
        world.remove_workpiece(loc.machine, loc.slot, wp.id)
    h = MachineHall(world, ["C-BS", "C-CS1", "C-SS"])
    h.feedback = []
    h.add_listener(h.feedback.append)
    return h


def run(world, hall, seconds):
    end = world.time + seconds
    while world.time < end - 1e-9:
        world.step(0.02)
        hall.update()


def test_a_step_takes_the_festo_time_and_reports_busy_then_idle(world, hall):
    hall.submit("C-BS", Command("GET_BASE", ("RED",)))
    hall.update()
    t0 = world.time
    run(world, hall, 2.0)
    busy = [(f.value, f.time - t0) for f in hall.feedback if f.what == "busy"]
    assert busy[0] == (True, 0.0)
    assert busy[1][0] is False and busy[1][1] == pytest.approx(Durations().base_dispense, abs=0.03)
    hall.feedback.clear()
    hall.submit("C-BS", Command("MOVE_CONVEYOR", ("TO_OUTPUT", "OUT")))
    run(world, hall, 3.0)
    order = [(f.what, f.value) for f in hall.feedback]
    assert order == [("busy", True), ("ready", True), ("busy", False)]       # WP before IDLE
    assert world.workpiece_at("C-BS", "output").base == "BASE_RED"


def test_a_full_output_stops_the_belt_and_a_mount_without_a_cap_does_nothing(world, hall):
    world.spawn_workpiece("C-CS1", "output", "BASE_BLACK")            # nobody took the last product
    world.spawn_workpiece("C-CS1", "input", "BASE_RED")
    for cmd in (Command("MOVE_CONVEYOR", ("TO_OUTPUT", "MID")), Command("CAP_ACTION", ("MOUNT",)),
                Command("MOVE_CONVEYOR", ("TO_OUTPUT", "OUT"))):
        hall.submit("C-CS1", cmd)
    run(world, hall, 25.0)
    m = hall["C-CS1"]
    texts = [r.text for r in m.records]
    assert any("no cap buffered" in t for t in texts)
    assert any("output is occupied" in t for t in texts)
    assert world.workpiece_at("C-CS1", "input").cap is None and not m.busy
    hall.submit("C-CS1", Command("RESET"))
    run(world, hall, 0.1)
    assert world.workpiece_at("C-CS1", "input") is None                # the referee clears the belt


def test_storage_refuses_an_empty_slot_and_keeps_what_it_stores(world, hall):
    hall.submit("C-SS", Command("RETRIEVE", ((3, 3),)))                 # never filled
    run(world, hall, 18.0)
    assert world.workpiece_at("C-SS", "input") is None
    assert any("empty" in r.text for r in hall["C-SS"].records)
    assert (0, 1) in hall["C-SS"].storage and len(hall["C-SS"].storage) == 6


def test_unknown_machines_are_refused(world, hall):
    with pytest.raises(KeyError, match="C-RS1"):
        hall.submit("C-RS1", Command("RESET"))
    with pytest.raises(KeyError, match="no station"):
        MachineHall(world, ["C-XX"])
