"""What the robot's backend tells the agent's RobotStatus: its capabilities,
whether it holds a workpiece, its battery.  A backend that cannot say (none,
no such capability, an error reading it) gives nothing instead of failing
the status."""
from __future__ import annotations

from ..backend import Backend, BackendError, Capability


def capabilities(backend: Backend | None) -> Capability:
    try:
        return backend.capabilities if backend is not None else Capability.NONE
    except Exception:
        return Capability.NONE


def holding(backend: Backend | None) -> bool | None:
    """Whether the gripper holds a workpiece; None when the robot cannot tell."""
    if backend is None or not (capabilities(backend) & Capability.GRIPPER):
        return None
    try:
        return backend.holding()
    except BackendError:
        return None


def fill_battery(status, backend: Backend | None) -> None:
    """The battery's voltage (and charge, when known) into a RobotStatus."""
    if not capabilities(backend) & Capability.BATTERY:
        return
    try:
        bat = backend.battery()
    except BackendError:
        return
    status.battery_voltage = bat.voltage
    if bat.soc is not None:
        status.battery_fraction = bat.soc
