"""Scripted-backend doubles of the skill nodes, to run the real task trees
without a world: each double has the real node's ports (it subclasses it),
acts on the scripted backend (drive, gripper) and fails the way the skill
does when the backend does (a drive fault: NAVIGATION_FAILED; an empty
gripper after closing: GRAB_FAILED; a full one after opening:
PUT_FAILED).  :class:`Hands` plays the workpiece: closing the gripper puts
one in it (unless a miss is scripted), opening takes it out, by appending
to the scripted backend's ``holding`` readings.
"""
from __future__ import annotations

from py_trees.common import Status

from rll_bt.backend import BackendError, Capability
from rll_bt.tree import default_registry, write_error
from skills import nodes as S

CALLS: list[tuple[str, dict]] = []      # (node type, port values) of every double started


class Double:
    """Mixin: ``act()`` at the start, then ``seconds`` of running, then ``finish()``."""
    requires_services = ()
    requires_capabilities = Capability.NONE
    seconds = 1.0
    fail_code = "NAVIGATION_FAILED"

    def initialise(self):
        CALLS.append((self.node_type, {p: getattr(self, p) for p, port in self.ports.items()
                                       if port.direction == "in"}))
        self._until = self.ctx.clock.now() + self.seconds
        self._broken = None
        try:
            self.act(self.ctx.backend)
        except BackendError as exc:
            self._broken = str(exc)

    def update(self):
        if self._broken is not None:
            # a fault message that says the pose is lost fails the way a lost localisation does
            code = "LOCALISATION_LOST" if "pose lost" in self._broken else self.fail_code
            return self.fail(code, self._broken)
        if self.ctx.clock.now() < self._until:
            return Status.RUNNING
        try:
            return self.finish(self.ctx.backend)
        except BackendError as exc:
            return self.fail(self.fail_code, str(exc))

    def terminate(self, new_status):
        if new_status is Status.INVALID:
            self.ctx.backend.stop()

    def fail(self, code, message):
        write_error(self._bb, code, message, self.name)
        self.ctx.backend.stop()
        return Status.FAILURE

    def act(self, backend):
        pass

    def finish(self, backend):
        backend.stop()
        return Status.SUCCESS


class Approach(Double, S.ApproachStationNode):
    """Double of approach_station: drives forward for 2 s."""
    seconds = 2.0

    def act(self, backend):
        backend.drive(0.2, 0.0, 0.0)


class BackOff(Double, S.BackOff):
    """Double of back_off: drives backwards for 1 s."""

    def act(self, backend):
        backend.drive(-0.1, 0.0, 0.0)


class Relocalise(Double, S.RelocaliseNode):
    """Double of relocalise: turns for 2 s."""
    seconds = 2.0
    fail_code = "LOCALISATION_LOST"

    def act(self, backend):
        backend.drive(0.0, 0.0, 0.5)


class Explore(Double, S.ExploreZoneNode):
    """Double of explore_zone: drives around for 3 s and finds nothing."""
    seconds = 3.0

    def act(self, backend):
        backend.drive(0.3, 0.0, 0.2)

    def finish(self, backend):
        backend.stop()
        self.found = []
        return Status.SUCCESS


class Drive(Double):
    """Mixin of the navigation doubles: drive forward for 2 s (NAVIGATION_FAILED on a drive fault)."""
    seconds = 2.0

    def act(self, backend):
        backend.drive(0.3, 0.0, 0.0)


class NavigatePose(Drive, S.NavigateToPose):
    """Double of navigate_to_pose."""


class NavigateZone(Drive, S.NavigateToZone):
    """Double of navigate_to_zone."""


class Grab(Double, S.Grab):
    """Double of grab: closes the gripper; GRAB_FAILED when it holds nothing 1 s later."""
    fail_code = "GRIPPER_ERROR"

    def act(self, backend):
        backend.gripper_close()

    def finish(self, backend):
        holding = bool(backend.holding())
        self.holding = holding                  # the output port
        if not holding:
            return self.fail("GRAB_FAILED", "the gripper is empty after the grab")
        return Status.SUCCESS


class GrabFromShelf(Double, S.GrabFromShelfNode):
    """Double of grab_from_shelf: closes the gripper; GRAB_FAILED "no workpiece found" when it holds
    nothing 1 s later (as if every slot had been tried)."""
    fail_code = "GRIPPER_ERROR"

    def act(self, backend):
        backend.gripper_close()

    def finish(self, backend):
        if not backend.holding():
            return self.fail("GRAB_FAILED", f"no workpiece found on {self.machine}'s shelf")
        self.slot = 0
        return Status.SUCCESS


class Put(Double, S.Put):
    """Double of put: opens the gripper; PUT_FAILED when it still holds something 1 s later."""
    fail_code = "GRIPPER_ERROR"

    def act(self, backend):
        backend.gripper_open()

    def finish(self, backend):
        if backend.holding():
            return self.fail("PUT_FAILED", "the workpiece is still in the gripper")
        return Status.SUCCESS


class Localised(S.Localised):
    """Double of localised: the scripted backend's ``confidence`` reading (default 1)."""
    requires_services = ()

    def update(self):
        r = self.ctx.backend._reading("confidence")
        conf = float(r["value"]) if r else 1.0
        CALLS.append(("localised", {"confidence": conf}))
        return Status.SUCCESS if conf >= self.min_confidence else Status.FAILURE


REGISTRY = default_registry().child()
for _cls, _name in ((Approach, "approach_station"), (BackOff, "back_off"), (Relocalise, "relocalise"),
                    (Explore, "explore_zone"), (NavigatePose, "navigate_to_pose"),
                    (NavigateZone, "navigate_to_zone"), (Grab, "grab"), (GrabFromShelf, "grab_from_shelf"),
                    (Put, "put"), (Localised, "localised")):
    REGISTRY.register(_cls, _name)


class Hands:
    """The workpiece in the gripper, as the scripted backend's ``holding`` readings.

    ``misses``: closes that catch nothing; ``stuck``: opens that do not let go.
    Call after every step (it looks at the gripper commands recorded since)."""

    def __init__(self, backend, holding: bool = False, misses: int = 0, stuck: int = 0):
        self.backend = backend
        self.misses, self.stuck = misses, stuck
        self.seen = 0
        self.closes = self.opens = 0
        backend.readings["holding"] = [{"t": 0.0, "value": holding}]

    def __call__(self, *_):
        cmds = self.backend.commands
        for _t, method, _args in cmds[self.seen:]:
            if method == "gripper_close":
                self.closes += 1
                if self.misses > 0:
                    self.misses -= 1
                else:
                    self._set(True)
            elif method == "gripper_open":
                self.opens += 1
                if self.stuck > 0:
                    self.stuck -= 1
                else:
                    self._set(False)
        self.seen = len(cmds)

    def _set(self, value: bool) -> None:
        self.backend.readings["holding"].append({"t": self.backend.elapsed(), "value": value})


def calls(kind: str | None = None) -> list:
    return [c for c in CALLS if kind is None or c[0] == kind]
