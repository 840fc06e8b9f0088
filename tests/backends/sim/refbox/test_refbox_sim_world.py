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
    world.run(20, callback=lambda t: g.tick())
    wp = world.workpiece_at("C-RS1", "output")
    assert (wp.base, wp.rings) == ("BASE_RED", (color,))
    assert world.lights("C-RS1") == {"RED": "OFF", "YELLOW": "ON", "GREEN": "OFF"}


def test_c0_cap_retrieve_mount_and_delivery_by_gripper_on_the_pybullet_world(world):
    """CS retrieve from its shelf, the cap-less carrier discarded, the cap mounted on a
    base from the BS, the product delivered at the DS and scored: every handling done by
    a robot's gripper in the PyBullet world."""
    from backends.sim.refbox import CSInstruction, DSInstruction
    g = RefboxGame("rcll2016", world.clock, world, seed=5, team_cyan="A", team_magenta="B")
    g.start()
    g.set_phase("PRODUCTION")
    o = next(o for o in g.orders if o.complexity == 0)
    o.active, o.begin, o.end = True, 0, 900
    cs = "C-CS1" if o.cap == "CAP_GREY" else "C-CS2"
    robot = world.add_robot("CYAN", 1)

    def tick(seconds):
        world.run(seconds, callback=lambda t: g.tick())

    def grab(machine, slot):
        world.teleport("CYAN", 1, world.station(machine).approach_pose(slot))
        robot.gripper.command("close", now=world.time)
        tick(3)
        held = world.held_workpiece("CYAN", 1)
        assert held is not None, f"nothing grabbed at {machine} {slot}"
        return held

    def put(machine, slot):
        world.teleport("CYAN", 1, world.station(machine).approach_pose(slot))
        robot.gripper.command("open", now=world.time)
        tick(3)
        assert world.held_workpiece("CYAN", 1) is None

    def wait_ready(machine, limit=60.0):
        for _ in range(int(limit)):
            if g.stations[machine].state == "READY-AT-OUTPUT":
                return
            tick(1)
        raise AssertionError(f"{machine} never got ready ({g.stations[machine].state})")

    carrier = grab(cs, "shelf1")
    assert carrier.cap == o.cap and carrier.base is not None
    assert g.prepare("CYAN", cs, CSInstruction("RETRIEVE_CAP"), "CYAN") == "prepared"
    put(cs, "input")
    wait_ready(cs)
    capless = grab(cs, "output")
    assert capless.cap is None
    world.teleport("CYAN", 1, world.station(cs).approach_pose("output", gap=0.6))   # discard
    robot.gripper.command("open", now=world.time)
    tick(3)
    assert world.held_workpiece("CYAN", 1) is None and world.workpiece_at(cs, "output") is None
    assert g.prepare("CYAN", "C-BS", BSInstruction("OUTPUT", o.base), "CYAN") == "prepared"
    wait_ready("C-BS")
    grab("C-BS", "output")
    assert g.prepare("CYAN", cs, CSInstruction("MOUNT_CAP"), "CYAN") == "prepared"
    put(cs, "input")
    wait_ready(cs)
    product = grab(cs, "output")
    assert (product.base, product.rings, product.cap) == (o.base, (), o.cap)
    before = g.points("CYAN")
    assert g.prepare("CYAN", "C-DS", DSInstruction(o.gate), "CYAN") == "prepared"
    put("C-DS", "input")
    tick(10)
    assert o.delivered["CYAN"] == 1
    assert g.points("CYAN") - before == 20 + 10            # in time, plus the cap mounted
    assert world.workpiece_at("C-DS", "input") is None


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


def test_2025_storage_station_on_the_pybullet_world():
    from backends.sim.refbox import SSInstruction
    from backends.sim.world import World
    world = World("rcll2025", seed=6)
    try:
        g = RefboxGame("rcll2025", world.clock, world, seed=6, team_cyan="A", team_magenta="B",
                       timing=Timing.from_profile(profile("rcll2025"), exploration=0))
        g.start()
        g.set_phase("PRODUCTION")
        assert world.lights("C-SS") == {"RED": "OFF", "YELLOW": "OFF", "GREEN": "ON"}
        robot = world.add_robot("CYAN", 1)
        g.prepare("CYAN", "C-BS", BSInstruction("OUTPUT", "BASE_SILVER"), "CYAN")
        world.run(5.5, callback=lambda t: g.tick())
        world.teleport("CYAN", 1, world.station("C-BS").approach_pose("output"))
        robot.gripper.command("close", now=world.time)
        world.run(3, callback=lambda t: g.tick())
        assert g.prepare("CYAN", "C-SS", SSInstruction("STORE", 1, 2, "spare"), "CYAN") == \
            "prepared"
        world.teleport("CYAN", 1, world.station("C-SS").approach_pose("input"))
        robot.gripper.command("open", now=world.time)
        world.run(3, callback=lambda t: g.tick())
        assert world.workpiece_at("C-SS", "input") is None          # taken into the shelf
        world.run(17, callback=lambda t: g.tick())
        assert g.stations["C-SS"].stored()[(1, 2)].base == "BASE_SILVER"
        world.run(5, callback=lambda t: g.tick())                    # WAIT-IDLE
        g.prepare("CYAN", "C-SS", SSInstruction("RETRIEVE", 1, 2), "CYAN")
        world.run(20.5, callback=lambda t: g.tick())
        assert world.workpiece_at("C-SS", "output").base == "BASE_SILVER"
        assert world.lights("C-SS") == {"RED": "OFF", "YELLOW": "ON", "GREEN": "BLINK"}
    finally:
        world.close()


def test_every_2025_message_fits_an_encrypted_datagram(harness25):
    from backends.sim.refbox import ReportEntry, StationConfig, Workpiece
    h = harness25(config=StationConfig(delivery_confirm=60)).production()
    g = h.game
    for n in range(1, 4):
        g.beacon(number=n, team_name="Caro", peer_name=f"robot-{n}", pose=(1.0, 2.0, 3.0))
    zones = g.profile.machine_zones("CYAN")
    g.machine_report("CYAN", [ReportEntry(None, t, z, None) for t in ("BS", "DS", "SS", "RS",
                                                                     "CS") for z in zones[:2]]
                     + [ReportEntry(m, None, zones[0], 0) for m in g.profile.machines("CYAN")],
                     "CYAN")
    m = Messages("rcll2025")
    codec = FrameCodec(MessageRegistry.from_message_set(msgs.message_set("rcll2025")),
                       key="k", max_frame=1024)
    out = [m.game_state(g), m.robot_info(g), m.machine_report_info(g, "CYAN"),
           m.attention("x" * 500, "CYAN")]
    ss = g.stations["C-SS"]
    for place in ss.status():
        ss.put_in_storage(place.shelf, place.slot, Workpiece("BASE_RED", ("RING_BLUE",)),
                          f"a long note about shelf {place.shelf} slot {place.slot}")
    for o in g.orders:
        o.active = True
        for _ in range(2):
            g.deliver(g.stations["C-DS"], Workpiece(o.base, o.rings, o.cap), 0, 10.0)
    out += [m.order_info(g), m.ring_info(g), m.machine_info(g, "CYAN"),
            m.machine_info(g, "MAGENTA")]
    for msg in out:
        assert msg.IsInitialized(), msg.DESCRIPTOR.name
        assert len(codec.encode(msg)) <= 1024, msg.DESCRIPTOR.name
    assert len(out[2].reported_types) == 7 and len(out[4].orders) == 11      # 1 BS, DS, SS; 2 RS, CS
    assert len(out[-2].machines) == 7 and len(out[-2].machines[2].status_ss) == 48
