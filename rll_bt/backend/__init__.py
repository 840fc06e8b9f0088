"""The backend interface every robot implementation provides.

Small enough to remember: drive, stop, odometry, laser, camera, gripper,
bumper, battery, capabilities, close.  Backends are found by name through the
``rll_bt.backends`` entry points, the way python-can finds its interfaces::

    with open_backend("sim", world=world, robot=1) as robot:
        robot.drive(0.3, 0.0, 0.0)

A backend that lacks a capability raises :class:`CapabilityError` from the
corresponding method and leaves the flag out of :attr:`Backend.capabilities`.
:func:`check_backend` (:mod:`.check`) tells whether a backend keeps this
contract.  The interface itself is in :mod:`.interface`, the data types in
:mod:`.types`.
"""
from __future__ import annotations

from .. import plugins
from .check import BackendCheck, BackendContractError, check_backend
from .interface import Backend, BackendError, BackendUnavailable, Capability, CapabilityError, SensorLost
from .types import (
    Battery,
    CameraExtrinsics,
    CameraImage,
    CameraIntrinsics,
    Detections,
    GripperState,
    GripperStatus,
    LaserScan,
    LightDetection,
    Odometry,
    Pose2D,
    TagDetection,
    light_state_code,
    wrap_angle,
)

__all__ = [
    "Backend", "BackendError", "BackendUnavailable", "CapabilityError", "Capability", "SensorLost",
    "open_backend", "available_backends", "check_backend", "BackendCheck", "BackendContractError",
    "Battery", "CameraExtrinsics", "CameraImage", "CameraIntrinsics", "Detections",
    "GripperState", "GripperStatus", "LaserScan", "LightDetection", "Odometry", "Pose2D",
    "TagDetection", "light_state_code", "wrap_angle",
]

ENTRY_POINT_GROUP = "rll_bt.backends"


def available_backends() -> list[str]:
    """Names of the installed backends."""
    return sorted(plugins.discover(ENTRY_POINT_GROUP))


def open_backend(name: str, **options) -> Backend:
    """Create the backend registered as ``name`` with ``options``."""
    try:
        factory = plugins.load(ENTRY_POINT_GROUP, name)
    except KeyError as exc:
        raise BackendUnavailable(str(exc.args[0])) from None
    backend = factory(**options)
    if not isinstance(backend, Backend):
        raise BackendError(f"backend {name!r} returned {type(backend).__name__}, not a Backend")
    return backend

