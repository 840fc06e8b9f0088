"""Take a workpiece from whichever slot of a cap station's shelf holds one.

A team server of the league says only ``retrieve {CS, shelf}``: the slot is
the robot's to find.  The gripper tells whether a slot held a workpiece
only once it has closed there, so :class:`GrabFromShelf` tries the slots one
after the other (slot 0 first, as the refbox's shelf is filled) with one
grab each (approach, reach in, close, check; before the next slot the
robot backs off from the face): the first slot whose grab
leaves a workpiece in the gripper is the one; a grab that finds nothing
there (the gripper's workpiece sensor saw nothing, or a gripper without
one closed on nothing) marks that slot empty and the next one is tried; a
grab that missed a carrier the sensor saw tries the next slot too.  The
robot remembers the slots it found empty or emptied itself (``ShelfMemory``
on its skill context) and tries them last, not never: another robot, or
the person refilling the shelf, may have changed them since.  Once it
knows every slot empty it forgets them, as a shelf is refilled once it is
empty (by a person at a real field, at once in rll-bt's world:
refbox-rules.md).  When all three slots were tried in one task and none
held a workpiece it fails with ``GRAB_FAILED`` and a message starting with
:data:`NOTHING_ON_SHELF` (the league's ``NO_WORKPIECE_FOUND``,
:mod:`rll_bt.agenttask.codes`); when a grab missed a carrier that was
there, with "no workpiece in the gripper" (``GRASPING_FAILED``).
"""
from __future__ import annotations

from rll_bt.agenttask.codes import NOTHING_FOUND

from ..activity import Activity, Sequence, Status
from ..errors import SkillError, SkillFailure
from ..navigation.motions import MoveRelative
from .places import place_for
from .station import GrabFrom, back_off_distance

SLOTS = (0, 1, 2)
#: how a failure of :class:`GrabFromShelf` with every slot empty begins (read by the agent)
NOTHING_ON_SHELF = NOTHING_FOUND


class ShelfMemory:
    """The shelf slots a robot knows to be empty: station name -> slots."""

    def __init__(self):
        self.empty: dict[str, set[int]] = {}

    def left(self, machine: str) -> list[int]:
        """The slots of ``machine`` not known to be empty (all of them once every one
        was known empty: the shelf has been refilled)."""
        gone = self.empty.get(machine, set())
        if gone >= set(SLOTS):
            gone.clear()
        return [s for s in SLOTS if s not in gone]

    def order(self, machine: str) -> list[int]:
        """Every slot of ``machine`` in the order to try them: those not known to be
        empty first, then those known empty (what is known may be out of date)."""
        first = self.left(machine)
        return first + [s for s in SLOTS if s not in first]

    def mark_empty(self, machine: str, slot: int) -> None:
        self.empty.setdefault(machine, set()).add(int(slot))


def shelf_memory(ctx) -> ShelfMemory:
    """The robot's :class:`ShelfMemory` (made on first use, kept on the skill context)."""
    mem = getattr(ctx, "shelves", None)
    if mem is None:
        mem = ctx.shelves = ShelfMemory()
    return mem


class GrabFromShelf(Activity):
    """Take a workpiece from the first slot of ``machine``'s shelf that holds one."""

    def __init__(self, ctx, machine: str, timeout: float | None = None):
        super().__init__(ctx, timeout)
        self.machine = machine
        self.name = f"grab from {machine} shelf"
        self.slot: int | None = None          # the slot tried now, then the one taken from
        self.tried: list[int] = []
        self.missed: list[int] = []           # slots where the grab missed a carrier the sensor saw
        self._grab: Activity | None = None

    def _on_start(self) -> None:
        self.slot, self.tried, self.missed, self._grab = None, [], [], None
        if self.ctx.backend.holding():
            raise SkillFailure(SkillError.INVALID_TASK, "the gripper already holds a workpiece")
        self._next()

    def _next(self) -> None:
        left = [s for s in shelf_memory(self.ctx).order(self.machine) if s not in self.tried]
        if not left and self.missed:
            raise SkillFailure(SkillError.GRAB_FAILED, f"no workpiece in the gripper: the grab missed the carrier "
                               f"on {self.machine}'s shelf slot {', '.join(map(str, self.missed))}")
        if not left:
            raise SkillFailure(SkillError.GRAB_FAILED, f"{NOTHING_ON_SHELF} on {self.machine}'s shelf (slots "
                               f"{', '.join(map(str, self.tried))} tried, each empty)")
        self.slot = left[0]
        ctx, place = self.ctx, place_for(self.machine, "SHELF", self.slot)
        steps = [lambda: GrabFrom(ctx, place)]
        if self.tried:          # docked at the slot just tried: away from the face first
            back = ctx.settings.manipulation.back_off
            steps.insert(0, lambda: MoveRelative(ctx, -back_off_distance(ctx, back), speed=0.2, partial=True))
        self.tried.append(self.slot)
        self._grab = Sequence(ctx, steps, name=f"grab from {place.describe()}").start()

    def _step(self, now: float) -> Status:
        status = self._grab.poll()
        if status is Status.RUNNING:
            return Status.RUNNING
        if status is Status.SUCCESS:
            shelf_memory(self.ctx).mark_empty(self.machine, self.slot)      # taken: empty now
            self.message = f"took the workpiece from {self.machine} shelf slot {self.slot}"
            return Status.SUCCESS
        if self._grab.error is SkillError.GRAB_FAILED and not self.ctx.backend.holding():
            if self._grab.message.startswith(NOTHING_FOUND) or self.ctx.backend.gripper_status().sensed is None:
                shelf_memory(self.ctx).mark_empty(self.machine, self.slot)      # nothing there
            else:
                self.missed.append(self.slot)                                   # there, not taken
            self._next()
            return Status.RUNNING
        raise SkillFailure(self._grab.error, self._grab.message)

    def _on_stop(self, status: Status) -> None:
        if self._grab is not None and self._grab.status is Status.RUNNING:
            self._grab.cancel()
        else:
            self.ctx.stop_base()
