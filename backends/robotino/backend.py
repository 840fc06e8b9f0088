"""``open_backend("robotino", ...)``: a Festo Robotino 3 over its USB serial
link, with the optional Carologistics gripper on a second serial device.

Options (all keywords):

``device``
    the base's tty; found by USB id 1E29:040D when None.
``gripper_device``
    the gripper Arduino's tty; no gripper capability when None.
``holding_sensor``
    ``HoldingSensor`` or its text form (``"distance:8>1.5"``, ``"analog:0<2"``,
    ``"digital:3"``, ``"digital:3=0"``) telling whether a workpiece is held;
    without it ``holding`` is None (the gripper cannot tell).
``gripper_config``
    a :class:`gripper.GripperConfig` (axis scale, speeds, timing, limits).
``cycle_time`` (0.005 .. 0.010 s), ``read_timeout`` (0.2 s), ``nodata_timeout``
(2 s), ``deadman`` (0.5 s), ``recover_bound`` (2), ``emergency_bumper`` (True),
``handshake_timeout`` (1 s), ``kinematics``, ``ramp_limits``, ``clock``
    passed to :class:`base.RobotinoBase`.

The base has no laser and no camera (those raise CapabilityError).
"""
from __future__ import annotations

from rll_bt.backend import (
    Backend,
    BackendError,
    Battery,
    Capability,
    CapabilityError,
    GripperStatus,
    Odometry,
    Pose2D,
    wrap_angle,
)
from rll_bt.clock import Clock, WallClock

from .base import BaseReadings, LinkStats, RobotinoBase
from .gripper import ArduinoGripper, GripperConfig
from .holding import HoldingSensor

EMPTY_VOLTAGE, FULL_VOLTAGE = 22.0, 24.5      # Fawkes' state-of-charge guess


class RobotinoBackend(Backend):
    name = "robotino"

    def __init__(self, device: str | None = None, *, gripper_device: str | None = None,
                 holding_sensor: HoldingSensor | str | None = None,
                 gripper_config: GripperConfig | None = None, clock: Clock | None = None,
                 **base_options):
        self.clock = clock or WallClock()
        if isinstance(holding_sensor, str):
            holding_sensor = HoldingSensor.parse(holding_sensor)
        self._holding_sensor = holding_sensor
        self._closed = False
        self._base = RobotinoBase(device, clock=self.clock, **base_options)
        self._base.open()
        self._gripper: ArduinoGripper | None = None
        if gripper_device:
            try:
                self._gripper = ArduinoGripper(gripper_device, config=gripper_config, clock=self.clock,
                                               holding=self._sensor_holding).open()
            except BaseException:
                self._base.close()
                raise

    # -- interface ----------------------------------------------------------
    @property
    def capabilities(self) -> Capability:
        caps = Capability.DRIVE | Capability.ODOMETRY | Capability.BUMPER | Capability.BATTERY
        return caps | Capability.GRIPPER if self._gripper is not None else caps

    def _check_open(self) -> None:
        if self._closed:
            raise BackendError("robotino backend is closed")

    def drive(self, vx: float, vy: float, omega: float) -> None:
        self._check_open()
        try:
            self._base.set_velocity(vx, vy, omega)
        except ValueError as exc:
            raise BackendError(str(exc)) from None

    def stop(self) -> None:
        if not self._closed:
            self._base.stop_now()

    def odometry(self) -> Odometry:
        stamp, x, y, phi, vx, vy, omega = self._base.odometry()
        return Odometry(stamp, Pose2D(x, y, wrap_angle(phi)), vx, vy, omega)

    def bumper(self) -> bool:
        return self._base.readings().bumper

    def battery(self) -> Battery:
        power = self._base.readings().power
        if power is None:
            raise BackendError("no power reading from the base yet")
        soc = min(1.0, max(0.0, (power.voltage - EMPTY_VOLTAGE) / (FULL_VOLTAGE - EMPTY_VOLTAGE)))
        return Battery(power.voltage, power.current, soc, bool(power.ext_power))

    def _need_gripper(self) -> ArduinoGripper:
        self._check_open()
        if self._gripper is None:
            raise CapabilityError(f"{self.name}: no gripper (pass gripper_device=...)")
        return self._gripper

    def gripper_open(self) -> None:
        self._need_gripper().open_gripper()

    def gripper_close(self) -> None:
        self._need_gripper().close_gripper()

    def gripper_move(self, x: float, y: float, z: float) -> None:
        self._need_gripper().move(x, y, z)

    def gripper_status(self) -> GripperStatus:
        return self._need_gripper().status()

    def holding(self) -> bool | None:
        return self._sensor_holding()

    def _sensor_holding(self) -> bool | None:
        if self._holding_sensor is None:
            return None
        return self._holding_sensor.evaluate(self._base.readings())

    def close(self) -> None:
        if self._closed:
            return
        self._closed = True
        if self._gripper is not None:
            self._gripper.close()
        self._base.close()

    # -- Robotino extras ------------------------------------------------------
    @property
    def versions(self) -> tuple[str, str]:
        """(hardware, firmware) version strings the base reported."""
        return self._base.versions

    def readings(self) -> BaseReadings:
        """Everything the base last reported (IR voltages, inputs, motors...)."""
        return self._base.readings()

    def link_stats(self) -> LinkStats:
        return self._base.stats()

    @property
    def base(self) -> RobotinoBase:
        """The driver underneath (cycle periods, raw tags)."""
        return self._base

    @property
    def gripper(self) -> ArduinoGripper | None:
        return self._gripper
