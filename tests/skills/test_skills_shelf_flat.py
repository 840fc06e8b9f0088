"""GrabFromShelf: a workpiece from whichever slot of a cap station's shelf holds one
(the league's ``retrieve {CS, shelf}`` names no slot), NO_WORKPIECE_FOUND's message
when none does, and the slots the robot knows empty."""
from rll_bt.agenttask import codes
from skills.activity import Status
from skills.errors import SkillError
from skills.manipulation import PutOnto, place_for
from skills.manipulation.shelf import NOTHING_ON_SHELF, GrabFromShelf, ShelfMemory, shelf_memory
from tests.support.skills_scene import Scene


def shelf(scene, *slots):
    """Workpieces on C-CS1's shelf slots ``slots``: slot -> workpiece."""
    return {s: scene.world.workpiece_at("C-CS1", "INPUT", scene.profile.mps.shelf_y[s]) for s in slots}


def test_the_robot_takes_the_slot_that_holds_a_workpiece():
    scene = Scene(seed=6)
    wps = shelf(scene, 2)
    grab = GrabFromShelf(scene.ctx, "C-CS1")
    assert scene.run(grab) is Status.SUCCESS, grab.message
    assert grab.slot == 2 and grab.tried == [0, 1, 2]          # 0 and 1 closed on nothing
    assert wps[2].held_by == 0
    assert scene.world.collisions == 0


def test_an_empty_shelf_is_no_workpiece_found():
    scene = Scene(seed=6)
    grab = GrabFromShelf(scene.ctx, "C-CS1")
    assert scene.run(grab) is Status.FAILURE
    assert grab.error is SkillError.GRAB_FAILED and grab.message.startswith(NOTHING_ON_SHELF), grab.message
    assert grab.tried == [0, 1, 2]
    assert codes.to_league(grab.error.value, grab.message, False) == "NO_WORKPIECE_FOUND"
    # any other failed grab stays GRASPING_FAILED
    assert codes.to_league("GRAB_FAILED", "no workpiece in the gripper after closing", False) == "GRASPING_FAILED"


def test_slots_known_empty_are_tried_last_not_never():
    # what the robot knows is out of date: the shelf was refilled and another robot took
    # slot 2 since; the robot tries slot 2 first, then the slots it knew empty
    scene = Scene(seed=6)
    wps = shelf(scene, 0, 1)
    for s in (0, 1):
        shelf_memory(scene.ctx).mark_empty("C-CS1", s)
    grab = GrabFromShelf(scene.ctx, "C-CS1")
    assert scene.run(grab) is Status.SUCCESS, grab.message
    assert grab.tried == [2, 0] and grab.slot == 0 and wps[0].held_by == 0


def test_a_missed_carrier_is_a_failed_grasp_not_an_empty_shelf():
    scene = Scene(seed=6)
    shelf(scene, 1)
    scene.world.fail_next_grab = True                   # the carrier on slot 1 is missed once
    for s in (0, 2):
        shelf_memory(scene.ctx).mark_empty("C-CS1", s)
    grab = GrabFromShelf(scene.ctx, "C-CS1")
    assert scene.run(grab) is Status.FAILURE
    assert grab.tried == [1, 0, 2] and grab.missed == [1]
    assert codes.to_league(grab.error.value, grab.message, False) == "GRASPING_FAILED", grab.message
    assert shelf_memory(scene.ctx).left("C-CS1") == [1]             # not taken for empty


def test_slots_known_empty_are_not_tried_again():
    scene = Scene(seed=6)
    wps = shelf(scene, 0, 1)
    first = GrabFromShelf(scene.ctx, "C-CS1")
    assert scene.run(first) is Status.SUCCESS and first.slot == 0
    assert scene.run(PutOnto(scene.ctx, place_for("C-CS1", "INPUT"))) is Status.SUCCESS
    second = GrabFromShelf(scene.ctx, "C-CS1")
    assert scene.run(second) is Status.SUCCESS, second.message
    assert second.tried == [1] and wps[1].held_by == 0           # slot 0 is the robot's own taking


def test_a_shelf_known_empty_is_taken_as_refilled():
    mem = ShelfMemory()
    for s in (0, 2):
        mem.mark_empty("C-CS1", s)
    assert mem.left("C-CS1") == [1] and mem.left("C-CS2") == [0, 1, 2]
    mem.mark_empty("C-CS1", 1)
    assert mem.left("C-CS1") == [0, 1, 2]           # refilled once empty (refbox-rules.md)
    scene = Scene()
    assert shelf_memory(scene.ctx) is shelf_memory(scene.ctx)      # one per robot, for the whole game
