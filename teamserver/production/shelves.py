"""The cap stations' shelves: which slot still holds a cap carrier, which one the robots cannot reach.

A cap station's shelf has three slots, each with a cap carrier at the start.  The
refbox rule (refbox-rules.md, both profiles): a shelf is refilled only once all
three of its slots are empty.  So the team server books every slot:

- *empty*: a robot grabbed its carrier (the RETRIEVE_CAP succeeded, or failed with
  the carrier in the gripper), or found nothing there (GRAB_FAILED after the
  grab's own recoveries); once all three are empty the shelf is full again;
- *out of reach*: the robot could not stand in front of it (ALIGN_FAILED "no
  room", or its docked sideways move there blocked: a wall or another station
  beside the shelf).  Not tried again at that
  station while a reachable slot holds a carrier.

A slot a wall leaves no room in front of (:mod:`.reach`, from the station's place
and rotation) is out of reach before any robot tries it.  A shelf whose carriers all
stand in such slots is *dry* (:meth:`CapShelves.dry`): it is never refilled (a
carrier stays on it), so its station retrieves no cap any more and the planner
leaves that retrieval out (``"<CS>:SHELF"`` among the places not to plan with,
:mod:`.world`).  The real generator may stand a cap station with its shelf by a
wall (refbox-rules.md, field generation): 2025 seed 4 has C-CS1's shelf against
the x = 7 wall with slot 0 out of reach, and robots
tried it again and again (seven RETRIEVE_CAPs of 45 s each at
20 % loss).  Slots found out of reach by a robot's failure are not dry-making: a
robot in the way is no wall.

:meth:`CapShelves.choose` gives a RETRIEVE_CAP the first slot that holds a carrier,
that no other robot's RETRIEVE_CAP under way is to empty, and that can be reached;
when none can, a slot out of reach that still holds one (the only cap source left
there; the shelf is not refilled while it holds a carrier), one a robot found out of
reach before one a wall leaves no room in front of, with a warning in the log.  The
books live in the knowledge base (``cap_shelves``: CS -> {"empty": [slots],
"unreachable": [slots]}).
"""
from __future__ import annotations

import logging

from ..knowledge import model as M
from ..knowledge.kb import KnowledgeBase
from .reach import Reach

log = logging.getLogger("teamserver.production")

SLOTS = (0, 1, 2)


def unreachable(error: str, text: str) -> bool:
    """Whether a RETRIEVE_CAP's failure says the robot could not get in front of its slot:
    no room there (ALIGN_FAILED), or the docked sideways move to it blocked
    (NAVIGATION_FAILED "move relative blocked": a wall or station beside the slot)."""
    text = text or ""
    return (error == "ALIGN_FAILED" and "no room" in text) or \
        (error == "NAVIGATION_FAILED" and "move relative blocked" in text)


class CapShelves:
    """Books of the cap stations' shelf slots (see the module doc)."""

    def __init__(self, kb: KnowledgeBase):
        self.kb = kb
        self.reach = Reach(kb)

    def _books(self) -> dict[str, dict[str, list[int]]]:
        return {cs: {k: list(v) for k, v in b.items()}
                for cs, b in self.kb.get("cap_shelves", {}).items()}

    def _slots(self, cs: str, what: str) -> set[int]:
        return set(self.kb.get("cap_shelves", {}).get(cs, {}).get(what, ()))

    def empty(self, cs: str) -> set[int]:
        """The slots of ``cs``'s shelf without a cap carrier."""
        return self._slots(cs, "empty")

    def unreachable(self, cs: str) -> set[int]:
        """The slots of ``cs``'s shelf the robots could not stand in front of, or that a
        wall leaves no room in front of."""
        return self._slots(cs, "unreachable") | self.reach.shelf_walled(cs)

    def dry(self, cs: str) -> bool:
        """Do ``cs``'s carriers all stand in slots a wall leaves no room in front of
        (see the module doc)?"""
        walled = self.reach.shelf_walled(cs)
        full = [s for s in SLOTS if s not in self.empty(cs)]
        return bool(walled) and all(s in walled for s in full)

    def emptied(self, cs: str, slot: int) -> None:
        """``slot`` of ``cs`` holds no carrier now; the shelf is full again once all are empty."""
        books = self._books()
        b = books.setdefault(cs, {})
        empty = set(b.get("empty", ())) | {int(slot)}
        if empty >= set(SLOTS):
            empty = set()
            log.info("%s's shelf is empty: refilled", cs)
        b["empty"] = sorted(empty)
        self.kb.set("cap_shelves", books)

    def out_of_reach(self, cs: str, slot: int) -> None:
        """The robots cannot stand in front of ``slot`` of ``cs``."""
        books = self._books()
        b = books.setdefault(cs, {})
        b["unreachable"] = sorted(set(b.get("unreachable", ())) | {int(slot)})
        self.kb.set("cap_shelves", books)
        log.warning("%s shelf slot %d cannot be reached: not tried again while another slot "
                    "there holds a cap", cs, slot)

    def outcome(self, task: M.Task, succeeded: bool, error: str, text: str,
                holding: bool | None) -> None:
        """Book a RETRIEVE_CAP's result on its shelf slot."""
        if task.kind != M.RETRIEVE_CAP or task.params.get("shelf_slot") is None or not task.machine:
            return
        cs, slot = task.machine, int(task.params["shelf_slot"])
        if succeeded or holding:
            self.emptied(cs, slot)
        elif error == "GRAB_FAILED":
            log.info("%s shelf slot %d: nothing to grab, empty", cs, slot)
            self.emptied(cs, slot)
        elif unreachable(error, text):
            self.out_of_reach(cs, slot)

    def taken(self, cs: str, but: int | None = None) -> set[int]:
        """The slots of ``cs`` that a RETRIEVE_CAP sent to a robot and not yet ended (other
        than task ``but``) is on its way to empty."""
        return {int(t.params["shelf_slot"]) for t in self.kb.open_tasks()
                if t.kind == M.RETRIEVE_CAP and t.machine == cs and t.state == M.ASSIGNED
                and t.id != but and t.params.get("shelf_slot") is not None}

    def choose(self, cs: str, task: int | None = None) -> int:
        """The slot RETRIEVE_CAP ``task`` at ``cs`` takes its carrier from (see the module
        doc).  A slot another robot is on its way to empty is left to it while another
        slot holds a carrier; when none does, two robots may go to one slot (the second
        finds it empty, and the shelf is refilled once it is)."""
        empty, taken = self.empty(cs), self.taken(cs, task)
        full = [s for s in SLOTS if s not in empty]
        free = [s for s in full if s not in taken] or full
        reach = [s for s in free if s not in self.unreachable(cs)]
        if reach:
            return reach[0]
        if not free:                        # (all empty is booked as refilled)
            return SLOTS[0]
        # a slot a robot found out of reach (a robot in the way, a move stopped a centimetre
        # short) before one a wall leaves no room in front of: 2025 seed 4 at 20 % loss, slot 1
        # of C-CS1 (0.26 m from the wall, in reach) booked out of reach once, and four robots
        # in turn sent to walled slot 0 over 200 s while a grey cap stood in slot 1
        walled = self.reach.shelf_walled(cs)
        pick = min(free, key=lambda s: (s in walled, s))
        log.warning("%s: no shelf slot the robots can reach holds a cap (slots %s out of reach, "
                    "%s empty; the shelf is refilled only once all are empty): trying slot %d, "
                    "the only cap source left there", cs, sorted(self.unreachable(cs)),
                    sorted(empty), pick)
        return pick
