"""Tree node types the agent's task trees need beyond the skills
(registered through the ``rll_bt.nodes`` entry point ``agent``).

- ``drop_workpiece``: let go of the held workpiece where the robot stands
  (a discard without a station);
- ``wait_station``: wait until the refbox shows a station in a state (a
  station PREPARED before its workpiece goes on the input).
"""
from __future__ import annotations

from py_trees.common import Status

from ..backend import BackendError, Capability
from ..tree import Input, Node, node_type, write_error


@node_type("drop_workpiece")
class DropWorkpiece(Node):
    """Open the gripper where it is, letting go of the held workpiece (a
    discard without a station), and check after ``settle`` seconds that the
    gripper is empty: PUT_FAILED when it still holds something,
    GRIPPER_ERROR when the gripper refuses to open."""
    settle = Input(float, "seconds to wait after opening before checking", default=1.0)
    requires_capabilities = Capability.GRIPPER

    def initialise(self) -> None:
        self._until = self.ctx.clock.now() + max(0.0, float(self.settle))
        self._error = None
        try:
            self.ctx.backend.gripper_open()
        except BackendError as exc:
            self._error = str(exc)

    def update(self) -> Status:
        if self._error is not None:
            write_error(self._bb, "GRIPPER_ERROR", f"the gripper does not open: {self._error}", self.name)
            return Status.FAILURE
        if self.ctx.clock.now() < self._until:
            return Status.RUNNING
        try:
            holding = self.ctx.backend.holding()
        except BackendError as exc:
            write_error(self._bb, "GRIPPER_ERROR", f"cannot read the gripper: {exc}", self.name)
            return Status.FAILURE
        if holding:
            write_error(self._bb, "PUT_FAILED", "the workpiece is still in the gripper after opening", self.name)
            return Status.FAILURE
        return Status.SUCCESS


@node_type("wait_station")
class WaitStation(Node):
    """Wait until the refbox reports ``machine`` in one of ``states`` (comma separated;
    MachineInfo on the team channel, the agent's ``refbox_stations`` service): a
    robot puts a workpiece on a station's input only once it is PREPARED for it.
    MACHINE_BROKEN when the station is BROKEN or DOWN, TIMEOUT after ``timeout``
    seconds.  Without any MachineInfo at all (no refbox: a bench run) it succeeds
    at once.  While it waits the service's ``waiting`` names the station (the
    RobotStatus's ``waiting_at``: a team server prepares a 2025 station only then)."""
    machine = Input(str, "station, e.g. C-RS1")
    states = Input(str, "states to wait for, comma separated", default="PREPARED")
    timeout = Input(float, "seconds", default=90.0)

    def initialise(self) -> None:
        self._until = self.ctx.clock.now() + max(0.0, float(self.timeout))

    def terminate(self, new_status: Status) -> None:
        view = self.ctx.services.get("refbox_stations")
        if view is not None and getattr(view, "waiting", None) == self.machine:
            view.waiting = None

    def update(self) -> Status:
        view = self.ctx.services.get("refbox_stations")
        if view is None or not view.heard:
            return Status.SUCCESS
        state = view.state(self.machine)
        wanted = {s.strip().upper() for s in str(self.states).split(",") if s.strip()}
        if state in wanted:
            return Status.SUCCESS
        view.waiting = self.machine
        if state in ("BROKEN", "DOWN"):
            write_error(self._bb, "MACHINE_BROKEN", f"{self.machine} is {state}", self.name)
            return Status.FAILURE
        if self.ctx.clock.now() >= self._until:
            write_error(self._bb, "TIMEOUT", f"{self.machine} stayed {state}, never "
                        f"{'/'.join(sorted(wanted))}", self.name)
            return Status.FAILURE
        return Status.RUNNING
