import math

import pytest

from backends.sim import SimBackend, SlotError
from rll_bt.backend import BackendError, GripperState, Pose2D


def settle(world, bot, seconds=1.0):
    world.step(seconds)
    return bot.gripper_status()


def test_pick_from_output_carry_and_put_on_input(world):
    events = []
    world.add_slot_listener(events.append)
    bs, rs = world.station("C-BS"), world.station("C-RS1")
    wp = world.spawn_workpiece("C-BS", "output", "BASE_RED")
    bot = SimBackend(world, ("CYAN", 1), pose=bs.approach_pose("output"))
    assert bot.gripper_status().is_open and not bot.holding()
    bot.gripper_close()
    assert bot.gripper_status().state is GripperState.MOVING
    st = settle(world, bot)
    assert st.state is GripperState.IDLE and not st.is_open and st.holding
    assert world.workpiece_at("C-BS", "output") is None
    assert world.held_workpiece("CYAN", 1) == wp
    assert [(e.kind, e.machine, e.slot, e.workpiece.id, e.robot) for e in events] == \
        [("take", "C-BS", "output", wp.id, ("CYAN", 1))]
    # the workpiece moves with the robot
    before = world.store.position(wp.id)
    for _ in range(5):
        bot.drive(-0.3, 0.0, 0.0)
        world.step(0.1)
    after = world.store.position(wp.id)
    assert math.hypot(after[0] - before[0], after[1] - before[1]) > 0.05
    # put it on the ring station's input
    world.teleport("CYAN", 1, rs.approach_pose("input"))
    bot.gripper_open()
    st = settle(world, bot)
    assert st.is_open and not st.holding
    assert world.workpiece_at("C-RS1", "input") == wp
    assert events[-1].kind == "put" and events[-1].machine == "C-RS1" and events[-1].slot == "input"
    x, y, z = world.store.position(wp.id)
    assert (x, y, z) == pytest.approx(rs.slot_point("input"))


def test_grab_needs_the_gripper_at_the_workpiece(world):
    bs = world.station("C-BS")
    world.spawn_workpiece("C-BS", "output", "BASE_BLACK")
    pose = bs.approach_pose("output", gap=0.1)          # 10 cm too far back
    bot = SimBackend(world, ("CYAN", 1), pose=pose)
    bot.gripper_close()
    assert not settle(world, bot).holding
    bot.gripper_open()
    bot.gripper_move(0.1, 0.0, 0.909)                   # reach forward instead
    bot.gripper_close()
    assert settle(world, bot, 2.0).holding


def test_grab_at_wrong_height_misses(world):
    bs = world.station("C-BS")
    world.spawn_workpiece("C-BS", "input", "BASE_SILVER")
    bot = SimBackend(world, ("CYAN", 1), pose=bs.approach_pose("input"))
    bot.gripper_move(0.0, 0.0, 0.6)
    bot.gripper_close()
    assert not settle(world, bot, 4.0).holding
    assert world.workpiece_at("C-BS", "input") is not None


def test_failed_grab_leaves_the_workpiece(world):
    bs = world.station("C-BS")
    wp = world.spawn_workpiece("C-BS", "output", "BASE_RED")
    bot = SimBackend(world, ("CYAN", 1), pose=bs.approach_pose("output"), grab_failure=1.0)
    bot.gripper_close()
    st = settle(world, bot)
    assert not st.is_open and st.holding is False
    assert world.workpiece_at("C-BS", "output") == wp


def test_release_away_from_a_slot_drops_on_the_floor_and_floor_pick(empty_world):
    w = empty_world
    bot = SimBackend(w, ("CYAN", 1), pose=Pose2D(-2.0, 3.0, 0.0))
    wp = w.spawn_workpiece_on_floor(-2.0 + 0.25, 3.0, "BASE_RED")
    bot.gripper_move(0.0, 0.0, 0.011)
    bot.gripper_close()
    assert settle(w, bot, 10.0).holding
    bot.gripper_move(0.0, 0.0, 0.5)
    for _ in range(10):
        bot.drive(0.0, 0.0, 0.5)
        w.step(0.1)
    bot.gripper_open()
    assert not settle(w, bot, 6.0).holding
    (found, loc), = w.workpieces()
    assert found == wp and loc.kind == "floor"
    gp = w.gripper_point(bot.robot)
    assert loc.xy == pytest.approx(gp[:2])


def test_gripper_rejects_moves_outside_its_range(world):
    bot = SimBackend(world, ("CYAN", 1))
    with pytest.raises(BackendError, match="outside"):
        bot.gripper_move(0.5, 0.0, 0.9)
    with pytest.raises(BackendError, match="outside"):
        bot.gripper_move(0.0, 0.0, 1.5)


def test_cap_station_shelf_and_ring_station_slide(world):
    cs, rs = world.station("C-CS1"), world.station("C-RS2")
    carrier = world.spawn_workpiece("C-CS1", "shelf1", "BASE_RED", cap="CAP_GREY")
    bot = SimBackend(world, ("CYAN", 1), pose=cs.approach_pose("shelf1"))
    bot.gripper_close()
    assert settle(world, bot).holding
    assert world.workpiece_at("C-CS1", "shelf1") is None
    world.teleport("CYAN", 1, rs.approach_pose("slide"))
    bot.gripper_open()
    settle(world, bot)
    assert world.workpieces_at("C-RS2", "slide") == (carrier,)
    world.spawn_workpiece("C-RS2", "slide", "BASE_BLACK")
    assert len(world.workpieces_at("C-RS2", "slide")) == 2
    assert world.remove_workpiece("C-RS2", "slide") == carrier
    assert len(world.workpieces_at("C-RS2", "slide")) == 1


def test_refbox_station_api(world):
    wp = world.spawn_workpiece("M-RS1", "input", "BASE_BLACK")
    with pytest.raises(SlotError, match="full"):
        world.spawn_workpiece("M-RS1", "input", "BASE_RED")
    with pytest.raises(KeyError, match="slots"):
        world.spawn_workpiece("M-RS1", "shelf0", "BASE_RED")
    with pytest.raises(KeyError, match="no station"):
        world.workpiece_at("X-RS1", "input")
    with pytest.raises(ValueError, match="base colour"):
        world.spawn_workpiece("M-RS1", "output", "BASE_PINK")
    one = world.modify_workpiece("M-RS1", "input", add_ring="RING_GREEN")
    assert one.id == wp.id and one.rings == ("RING_GREEN",)
    moved = world.move_workpiece("M-RS1", "input", "output")
    assert world.workpiece_at("M-RS1", "input") is None and world.workpiece_at("M-RS1", "output") == moved
    capped = world.modify_workpiece("M-RS1", "output", cap="CAP_BLACK")
    assert capped.cap == "CAP_BLACK"
    assert world.modify_workpiece("M-RS1", "output", cap=None).cap is None
    assert world.remove_workpiece("M-RS1", "output").id == wp.id
    assert world.remove_workpiece("M-RS1", "output") is None
    assert "output" not in world.station("M-DS").slots
    # lights
    world.set_lights("M-RS1", red="BLINK", green="ON")
    assert world.lights("M-RS1") == {"RED": "BLINK", "YELLOW": "OFF", "GREEN": "ON"}
    codes = set()
    for _ in range(4):
        codes.add(world.visible_light_code("M-RS1"))
        world.step(0.125)
    assert codes == {1, 5}
    with pytest.raises(ValueError, match="light state"):
        world.set_lights("M-RS1", red="FLASH")


def test_listener_may_change_the_world(world):
    """A referee box reacting to a put (moving the workpiece on) inside the callback."""
    rs = world.station("C-RS1")

    def conveyor(ev):
        if ev.kind == "put" and ev.slot == "input":
            world.move_workpiece(ev.machine, "input", "output")

    world.add_slot_listener(conveyor)
    bot = SimBackend(world, ("CYAN", 1), pose=rs.approach_pose("input"))
    world.spawn_workpiece_on_floor(0.0, 0.0, "BASE_RED")
    held = world.spawn_workpiece("C-RS1", "input", "BASE_SILVER")
    bot.gripper_close()
    settle(world, bot)
    bot.gripper_open()
    settle(world, bot)
    assert world.workpiece_at("C-RS1", "output") == held


def test_the_workpiece_sensor_sees_what_a_close_would_take(world):
    bs = world.station("C-BS")
    bot = SimBackend(world, ("CYAN", 1), pose=bs.approach_pose("output"))
    assert bot.gripper_status().sensed is False                 # nothing on the output
    wp = world.spawn_workpiece("C-BS", "output", "BASE_RED")
    assert bot.gripper_status().sensed is True and not bot.holding()
    bot.gripper_close()
    st = settle(world, bot)
    assert st.holding and st.sensed and world.held_workpiece("CYAN", 1) == wp
    world.teleport("CYAN", 1, bs.approach_pose("input"))        # nothing there, one held
    assert bot.gripper_status().sensed is True
