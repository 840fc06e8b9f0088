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
``robot_config``
    a robot configuration file (:mod:`.config`; a path, dict or
    :class:`~.config.RobotConfig`): the base's device, the gripper, and the
    laser and camera (:class:`~.parts.SensorParts`) with their mounting
    poses.  Keywords given here win over the file.
``cycle_time`` (0.005 .. 0.010 s), ``read_timeout`` (0.2 s), ``nodata_timeout``
(2 s), ``deadman`` (0.5 s), ``recover_bound`` (2), ``emergency_bumper`` (True),
``handshake_timeout`` (1 s), ``kinematics``, ``ramp_limits``, ``clock``
    passed to :class:`base.RobotinoBase`.

Without a configured laser or camera those raise CapabilityError.  With
them, a device that stops delivering (port closed, no data for the
configured ``faults.stale`` seconds) stops the base at once (a watcher
thread) and makes :meth:`drive`, :meth:`laser_scan` or :meth:`camera_image`
raise :class:`~rll_bt.backend.SensorLost` until it is back (its driver
reopens it by itself).
"""
from __future__ import annotations

import logging
import threading
from dataclasses import replace

from rll_bt.backend import (
    Backend,
    BackendError,
    Battery,
    CameraImage,
    Capability,
    CapabilityError,
    GripperStatus,
    LaserScan,
    Odometry,
    Pose2D,
    wrap_angle,
)
from rll_bt.clock import Clock, WallClock

from .base import BaseReadings, LinkStats, RobotinoBase
from .gripper import ArduinoGripper, GripperConfig
from .holding import HoldingSensor

log = logging.getLogger(__name__)

EMPTY_VOLTAGE, FULL_VOLTAGE = 22.0, 24.5      # Fawkes' state-of-charge guess


class RobotinoBackend(Backend):
    name = "robotino"

    def __init__(self, device: str | None = None, *, gripper_device: str | None = None,
                 holding_sensor: HoldingSensor | str | None = None,
                 gripper_config: GripperConfig | None = None, clock: Clock | None = None,
                 robot_config=None, **base_options):
        self.clock = clock or WallClock()
        self.config = None
        if robot_config is not None:
            from .config import as_config
            self.config = cfg = as_config(robot_config)
            if cfg.base["type"] != "robotino3":
                raise BackendError(f"{cfg.path or 'robot config'}: base type {cfg.base['type']} is not a "
                                   "Robotino 3 serial base (open it with the robotino_rest backend)")
            device = device or cfg.base.get("device")
            for key in ("cycle_time", "emergency_bumper"):
                if key in cfg.base:
                    base_options.setdefault(key, cfg.base[key])
            if "startup_wait" in cfg.faults:        # the base's first reading is its answer to the handshake
                base_options.setdefault("handshake_timeout", max(cfg.startup_wait, 0.1))
            if cfg.gripper:
                gripper_device = gripper_device or cfg.gripper["device"]
                holding_sensor = holding_sensor or cfg.gripper.get("holding_sensor")
                self._gripper_origin = tuple(cfg.gripper.get("origin", (0.0, 0.0, 0.0)))
        if isinstance(holding_sensor, str):
            holding_sensor = HoldingSensor.parse(holding_sensor)
        self._holding_sensor = holding_sensor
        self._closed = False
        self._parts = None
        if not hasattr(self, "_gripper_origin"):
            self._gripper_origin = (0.0, 0.0, 0.0)
        self.sensor_stops = 0
        self._stop_watch = threading.Event()
        self._watcher: threading.Thread | None = None
        self._base = RobotinoBase(device, clock=self.clock, **base_options)
        self._base.open()
        self._gripper: ArduinoGripper | None = None
        try:
            if gripper_device:
                self._gripper = ArduinoGripper(gripper_device, config=gripper_config, clock=self.clock,
                                               holding=self._sensor_holding).open()
            if self.config is not None and (self.config.laser or self.config.camera):
                from .parts import SensorParts
                self._parts = SensorParts(self.config, self.clock).start()
                self._watcher = threading.Thread(target=self._watch, name="robotino-sensor-watch", daemon=True)
                self._watcher.start()
        except BaseException:
            if self._gripper is not None:
                self._gripper.close()
            self._base.close()
            raise

    # -- interface ----------------------------------------------------------
    @property
    def capabilities(self) -> Capability:
        caps = Capability.DRIVE | Capability.ODOMETRY | Capability.BUMPER | Capability.BATTERY
        if self._gripper is not None:
            caps |= Capability.GRIPPER
        if self._parts is not None and self._parts.laser is not None:
            caps |= Capability.LASER
        if self._parts is not None and self._parts.camera is not None:
            caps |= Capability.CAMERA
        return caps

    # -- sensors -------------------------------------------------------------------
    @property
    def parts(self):
        """The laser and camera drivers (:class:`~.parts.SensorParts`), or None."""
        return self._parts

    def _watch(self) -> None:
        """Stop the base the moment a sensor is lost (and keep it stopped)."""
        was_lost = False
        while not self._stop_watch.wait(0.02):
            lost = self._parts.lost()
            if lost is not None:
                self._base.stop_now()
                if not was_lost:
                    self.sensor_stops += 1
                    log.warning("%s; base stopped", lost)
            elif was_lost:
                log.warning("sensors back; driving allowed again")
            was_lost = lost is not None

    def laser_scan(self) -> LaserScan | None:
        if self._parts is None or self._parts.laser is None:
            raise CapabilityError(f"{self.name}: no laser (configure one in the robot config)")
        return self._parts.laser_scan()

    def camera_image(self, camera: str = "front") -> CameraImage | None:
        if self._parts is None or self._parts.camera is None:
            raise CapabilityError(f"{self.name}: no camera (configure one in the robot config)")
        return self._parts.camera_image(camera)

    def _check_open(self) -> None:
        if self._closed:
            raise BackendError("robotino backend is closed")

    def drive(self, vx: float, vy: float, omega: float) -> None:
        self._check_open()
        if self._parts is not None and (vx or vy or omega):
            lost = self._parts.lost()
            if lost is not None:
                self._base.stop_now()
                raise lost
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
        ox, oy, oz = self._gripper_origin
        self._need_gripper().move(x - ox, y - oy, z - oz)

    def gripper_status(self) -> GripperStatus:
        st = self._need_gripper().status()
        if any(self._gripper_origin):
            st = replace(st, position=tuple(v + o for v, o in zip(st.position, self._gripper_origin)))
        return st

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
        self._stop_watch.set()
        if self._watcher is not None:
            self._watcher.join(timeout=1.0)
        if self._parts is not None:
            self._parts.close()
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
