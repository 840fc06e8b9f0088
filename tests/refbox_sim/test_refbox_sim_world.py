"""The refbox game on the PyBullet world's station API, a robot's gripper doing the handling;
and every outgoing message fitting a 1024-byte encrypted datagram."""
from __future__ import annotations

import pytest

from backends.sim.refbox import BSInstruction, RefboxGame, RSInstruction, Timing
from backends.sim.refbox.messages import Messages
from rll_bt import msgs
from rll_bt.comm import FrameCodec, MessageRegistry
from rll_bt.rules import profile


@pytest.fixture
def world():
    from backends.sim.world import World
    w = World("rcll2016", seed=5)
    yield w
    w.close()


def test_game_on_the_pybullet_world(world):
    g = RefboxGame("rcll2016", world.clock, world, seed=5, team_cyan="A", team_magenta="B")
    assert g.layout is world.layout                       # the world's placement is the game's
    assert world.workpiece_at("C-CS1", "shelf0").cap == "CAP_GREY"
    g.start()
    g.set_phase("PRODUCTION")
    assert world.lights("C-BS") == {"RED": "OFF", "YELLOW": "OFF", "GREEN": "ON"}
    robot = world.add_robot("CYAN", 1)
    g.prepare("CYAN", "C-BS", BSInstruction("OUTPUT", "BASE_RED"), "CYAN")
    world.run(5.5, callback=lambda t: g.tick())
    assert world.workpiece_at("C-BS", "output").base == "BASE_RED"
    world.teleport("CYAN", 1, world.station("C-BS").approach_pose("output"))
    robot.gripper.command("close", now=world.time)
    world.run(3, callback=lambda t: g.tick())
    assert world.held_workpiece("CYAN", 1).base == "BASE_RED"
    assert g.stations["C-BS"].state == "WAIT-IDLE"        # the take was seen
    color = next(c for c in g.rs_colors("C-RS1") if g.ring_costs[c] == 0)
    g.prepare("CYAN", "C-RS1", RSInstruction(color), "CYAN")
    world.teleport("CYAN", 1, world.station("C-RS1").approach_pose("input"))
    robot.gripper.command("open", now=world.time)
    world.run(3, callback=lambda t: g.tick())
    assert g.stations["C-RS1"].state == "PROCESSING"
    world.run(16, callback=lambda t: g.tick())
    wp = world.workpiece_at("C-RS1", "output")
    assert (wp.base, wp.rings) == ("BASE_RED", (color,))
    assert world.lights("C-RS1") == {"RED": "OFF", "YELLOW": "ON", "GREEN": "OFF"}


def test_every_message_fits_an_encrypted_datagram(harness):
    h = harness().exploration()
    g = h.game
    for n in range(1, 4):
        g.beacon(number=n, team_name="Caro", peer_name=f"robot-{n}", pose=(1.0, 2.0, 3.0))
        g.beacon(number=n, team_name="Grips", peer_name=f"robot-{n}", pose=(1.0, 2.0, 3.0))
    m = Messages("rcll2016")
    codec = FrameCodec(MessageRegistry.from_message_set(msgs.message_set("rcll2016")),
                       key="k", max_frame=1024)
    out = [m.exploration_info(g, g.rng("x")), m.game_state(g), m.robot_info(g), m.beacon(0.0),
           m.version_info(), m.machine_report_info(g, "CYAN"), m.attention("x" * 500, "CYAN")]
    g.set_phase("PRODUCTION")
    for o in g.orders:
        o.active = True
    out += [m.order_info(g), m.ring_info(g), m.machine_info(g, "CYAN"), m.machine_info(g, "MAGENTA")]
    for msg in out:
        assert msg.IsInitialized(), msg.DESCRIPTOR.name
        assert len(codec.encode(msg)) <= 1024
    assert len(out[-4].orders) == 8 and len(out[-2].machines) == 6
    assert Timing.from_profile(profile("rcll2016")).production == 900
