"""The cap stations' shelf slots: the team server sends a RETRIEVE_CAP only to a slot that
holds a cap carrier and that the robots can reach (teamserver/production/shelves.py), with
the refbox's refill rule (a shelf is refilled only once all three slots are empty)."""
from rll_bt import rules
from teamserver.knowledge import model as M
from teamserver.knowledge.kb import KnowledgeBase
from teamserver.production.shelves import CapShelves
from teamserver.server import ServerConfig
from tests.support.teamserver import Lockstep, production_setup, run_tasks

#: no caps retrieved ahead: every retrieval is for an order
ALONE = ServerConfig(prefill_caps=False)


class Shelf:
    """The cap station's shelf as the refbox and a robot see it: three carriers, refilled
    only once all three are gone; ``unreachable`` slots have no room for the robot."""

    def __init__(self, unreachable=()):
        self.full = {0, 1, 2}
        self.unreachable = set(unreachable)
        self.tried: list[tuple[int, str]] = []

    def retrieve(self, machine: str, slot: int) -> dict | None:
        """The robot's result of a retrieval at ``slot`` (None: it succeeded)."""
        if slot in self.unreachable:
            self.tried.append((slot, "no room"))
            return {"error": "ALIGN_FAILED",
                    "text": f"no room for the robot in front of {machine} input shelf{slot}"}
        if slot not in self.full:
            self.tried.append((slot, "empty"))
            return {"error": "GRAB_FAILED", "text": "nothing in the gripper after the grab"}
        self.tried.append((slot, "took"))
        self.full.discard(slot)
        if not self.full:
            self.full = {0, 1, 2}
        return None


def play(ls, shelf: Shelf, attempts: int, steps: int = 600) -> None:
    """Answer every task: a retrieval at C-CS2 as ``shelf`` says, everything else done;
    until ``attempts`` retrievals were tried."""
    def fail(agent, t):
        if t.WhichOneof("kind") == "retrieve_cap" and t.retrieve_cap.machine == "C-CS2":
            return shelf.retrieve(t.retrieve_cap.machine, t.retrieve_cap.shelf_slot)
        return None
    run_tasks(ls, lambda: len(shelf.tried) >= attempts, fail, steps)


def test_a_shelf_slot_out_of_reach_is_not_tried_while_a_reachable_one_holds_a_cap():
    ls = Lockstep(config=ALONE)
    production_setup(ls, [{"id": i} for i in range(1, 5)])
    shelf = Shelf(unreachable={0})
    play(ls, shelf, attempts=6)
    tried = shelf.tried
    assert len(tried) >= 6
    assert tried[:3] == [(0, "no room"), (1, "took"), (2, "took")]
    # slots 1 and 2 empty, slot 0 holds the last carrier (no refill before it is gone):
    # never an empty slot again, only the slot out of reach, the only cap source left
    assert all(t == (0, "no room") for t in tried[3:]), tried
    assert ls.server.production.cap_shelves.empty("C-CS2") == {1, 2}
    assert ls.server.production.cap_shelves.unreachable("C-CS2") == {0}
    ls.close()


def test_a_slot_found_empty_is_not_tried_again_until_the_shelf_is_refilled():
    ls = Lockstep(config=ALONE)
    production_setup(ls, [{"id": i} for i in range(1, 5)])
    shelf = Shelf()
    shelf.full = {0, 2}          # slot 1 taken before (a retrieval the server did not see end)
    play(ls, shelf, attempts=6)
    tried = shelf.tried
    assert tried[:3] == [(0, "took"), (1, "empty"), (2, "took")]
    assert [s for s, what in tried[3:6]] == [0, 1, 2]           # refilled: all three in turn
    assert all(what == "took" for _, what in tried[3:6])
    ls.close()


def test_a_shelf_slot_a_robot_grabbed_from_is_empty_and_the_shelf_refills_when_all_are():
    shelves = CapShelves(KnowledgeBase(rules.profile("rcll2016")))
    task = M.Task(1, M.RETRIEVE_CAP, {"machine": "C-CS1", "shelf_slot": 0})
    shelves.outcome(task, False, "NAVIGATION_FAILED", "", False)       # nothing known
    assert shelves.choose("C-CS1") == 0
    shelves.outcome(task, False, "PUT_FAILED", "", True)               # grabbed, then failed
    assert shelves.empty("C-CS1") == {0} and shelves.choose("C-CS1") == 1
    shelves.outcome(M.Task(2, M.RETRIEVE_CAP, {"machine": "C-CS1", "shelf_slot": 1}),
                    True, "NONE", "", False)
    assert shelves.choose("C-CS1") == 2
    shelves.outcome(M.Task(3, M.RETRIEVE_CAP, {"machine": "C-CS1", "shelf_slot": 2}),
                    False, "GRAB_FAILED", "nothing in the gripper after the grab", False)
    assert shelves.empty("C-CS1") == set() and shelves.choose("C-CS1") == 0     # refilled
    # the docked sideways move to slot 0 blocked by the wall beside it: out of reach
    shelves.outcome(task, False, "NAVIGATION_FAILED",
                    "move relative blocked 0.04 m short: something is in the way", False)
    assert shelves.unreachable("C-CS1") == {0} and shelves.choose("C-CS1") == 1


def test_two_retrievals_under_way_at_one_station_go_to_different_slots():
    kb = KnowledgeBase(rules.profile("rcll2016"))
    shelves = CapShelves(kb)

    def assign(tid: int) -> M.Task:
        t = M.Task(tid, M.RETRIEVE_CAP, {"machine": "C-CS1"}, state=M.ASSIGNED, robot=tid)
        t.params["shelf_slot"] = shelves.choose("C-CS1", t.id)
        kb.save_task(t)
        return t

    first, second = assign(1), assign(2)
    assert (first.params["shelf_slot"], second.params["shelf_slot"]) == (0, 1)
    # the first one's robot dropped out and its task is sent again: it keeps its own slot
    assert shelves.choose("C-CS1", first.id) == 0
    # slot 2 is found empty; the two under way hold the last carriers: a third robot is
    # sent to one of them rather than to an empty slot
    shelves.outcome(M.Task(9, M.RETRIEVE_CAP, {"machine": "C-CS1", "shelf_slot": 2}),
                    False, "GRAB_FAILED", "nothing in the gripper after the grab", False)
    assert assign(3).params["shelf_slot"] in (0, 1)
    # a retrieval at another station is not counted here
    other = M.Task(4, M.RETRIEVE_CAP, {"machine": "C-CS2", "shelf_slot": 0}, state=M.ASSIGNED)
    kb.save_task(other)
    assert shelves.choose("C-CS2", None) == 1 and shelves.choose("C-CS2", other.id) == 0
    # once a retrieval ended its slot is booked by its result, not by it being under way
    first.state = M.DONE
    kb.save_task(first)
    shelves.outcome(first, True, "NONE", "", False)
    assert shelves.empty("C-CS1") == {0, 2} and shelves.choose("C-CS1", 5) == 1
