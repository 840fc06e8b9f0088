"""The backend interface: :class:`Backend`, its :class:`Capability` flags and its errors."""
from __future__ import annotations

import abc
import enum

from .types import Battery, CameraImage, Detections, GripperStatus, LaserScan, Odometry


class BackendError(RuntimeError):
    """A backend could not do what was asked."""


class BackendUnavailable(BackendError):
    """The device, server or world behind a backend cannot be reached."""


class CapabilityError(BackendError):
    """The backend does not have the capability that was used."""


class SensorLost(BackendError):
    """A sensor the robot needs (``device``: "laser", "camera") stopped
    delivering: its port closed or no data came for too long.  The backend
    has stopped the base; skills fail with ``SENSOR_LOST``.  It passes once
    the device is back."""

    def __init__(self, device: str, message: str):
        super().__init__(message)
        self.device = device


class Capability(enum.Flag):
    NONE = 0
    DRIVE = enum.auto()
    ODOMETRY = enum.auto()
    LASER = enum.auto()
    CAMERA = enum.auto()
    GRIPPER = enum.auto()
    BUMPER = enum.auto()
    BATTERY = enum.auto()
    DETECTIONS = enum.auto()   # the backend reports tags and lights itself (simulation oracle)


class Backend(abc.ABC):
    """One robot.  Methods never block for long: they send a command or
    return the latest reading.  Velocities are in the robot frame."""

    #: the name this backend is registered under
    name: str = "abstract"

    @property
    @abc.abstractmethod
    def capabilities(self) -> Capability:
        """What this backend can do."""

    # -- motion -----------------------------------------------------------
    @abc.abstractmethod
    def drive(self, vx: float, vy: float, omega: float) -> None:
        """Command a body velocity (m/s, m/s, rad/s).  Backends keep the
        command alive; it is dropped when :meth:`stop` is called, or by the
        backend's own deadman when commands stop arriving."""

    def stop(self) -> None:
        """Stop the base at once."""
        self.drive(0.0, 0.0, 0.0)

    @abc.abstractmethod
    def odometry(self) -> Odometry:
        """Latest dead-reckoned pose and velocity."""

    # -- sensors ----------------------------------------------------------
    def laser_scan(self) -> LaserScan | None:
        """Latest laser scan, or None when none has arrived yet."""
        raise CapabilityError(f"{self.name}: no laser")

    def camera_image(self, camera: str = "front") -> CameraImage | None:
        """A camera frame, with intrinsics and extrinsics."""
        raise CapabilityError(f"{self.name}: no camera")

    def detections(self, camera: str = "front") -> Detections:
        """Tags and lights the backend itself perceives (``DETECTIONS``)."""
        raise CapabilityError(f"{self.name}: no built-in perception")

    def bumper(self) -> bool:
        raise CapabilityError(f"{self.name}: no bumper")

    def battery(self) -> Battery:
        raise CapabilityError(f"{self.name}: no battery reading")

    # -- gripper ----------------------------------------------------------
    def gripper_open(self) -> None:
        raise CapabilityError(f"{self.name}: no gripper")

    def gripper_close(self) -> None:
        raise CapabilityError(f"{self.name}: no gripper")

    def gripper_move(self, x: float, y: float, z: float) -> None:
        """Move the gripper's axes to an absolute position in metres."""
        raise CapabilityError(f"{self.name}: no gripper")

    def gripper_status(self) -> GripperStatus:
        raise CapabilityError(f"{self.name}: no gripper")

    def holding(self) -> bool | None:
        """Whether the gripper holds a workpiece (None when it cannot tell)."""
        return self.gripper_status().holding

    # -- life cycle -------------------------------------------------------
    def close(self) -> None:
        """Stop the robot and release the device.  Safe to call twice."""

    def __enter__(self):
        return self

    def __exit__(self, *exc) -> None:
        try:
            self.stop()
        except BackendError:
            pass
        finally:
            self.close()
