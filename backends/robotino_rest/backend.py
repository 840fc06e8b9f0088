"""``open_backend("robotino_rest", base_url="http://ROBOT")``: a Robotino 4
through its REST API.

The robot stops when ``/data/omnidrive`` is not refreshed within 200 ms, so a
background thread resends the current command every ``refresh`` s (default
0.1, at most 0.2) while it is non-zero, sends one zero command when it
becomes zero, and applies a host deadman (``deadman`` s, default 0.5) to
commands that stop arriving.  Sensors are read on demand (one GET each).

Options: ``base_url`` (default ``http://127.0.0.1``, i.e. on the robot's own
PC), ``timeout`` (s per request), ``refresh``, ``deadman``, ``method``
(``"POST"`` or ``"PUT"`` for omnidrive), ``sid``, ``laser_mount``
(:class:`Pose2D` of the laser in the robot frame), ``camera_extrinsics``,
``camera_hfov`` (rad; intrinsics are derived from the image size), ``clock``.
``robot_config`` (a robot configuration file, :mod:`backends.robotino.config`,
with ``base: {type: robotino4, url: ...}``) adds the same parts a Robotino
3 gets: the configured laser and camera replace ``/data/scan0`` and
``/cam0`` (a lost one stops the robot and raises
:class:`~rll_bt.backend.SensorLost`, as there), and the gripper Arduino
gives the gripper capability.  Battery is not offered (the API's power
fields are not documented).
"""
from __future__ import annotations

import logging
import math
import threading

import numpy as np

from rll_bt.backend import (
    Backend,
    BackendError,
    BackendUnavailable,
    CameraExtrinsics,
    CameraImage,
    CameraIntrinsics,
    Capability,
    CapabilityError,
    LaserScan,
    Odometry,
    Pose2D,
    wrap_angle,
)
from rll_bt.clock import Clock, WallClock

from .client import RestClient, RestError

log = logging.getLogger(__name__)

OMNIDRIVE = "/data/omnidrive"
MAX_REFRESH = 0.2


def _numbers(value, n: int | None, what: str) -> list[float]:
    if not isinstance(value, list) or (n is not None and len(value) < n):
        raise BackendError(f"{what}: expected a list of {n} numbers, got {str(value)[:80]}")
    try:
        return [float("nan") if v is None else float(v) for v in value]
    except (TypeError, ValueError):
        raise BackendError(f"{what}: non-numeric entries in {str(value)[:80]}") from None


class RobotinoRestBackend(Backend):
    name = "robotino_rest"

    def __init__(self, base_url: str = "http://127.0.0.1", *, timeout: float = 0.5,
                 refresh: float = 0.1, deadman: float = 0.5, method: str = "POST",
                 sid: str | None = "rll_bt", laser_mount: Pose2D = Pose2D(),
                 camera_extrinsics: CameraExtrinsics | None = None,
                 camera_hfov: float = math.radians(60.0), clock: Clock | None = None, robot_config=None):
        self.config = None
        if robot_config is not None:
            from backends.robotino.config import as_config
            self.config = as_config(robot_config)
            base_url = self.config.base.get("url", base_url)
        if not 0 < refresh <= MAX_REFRESH:
            raise ValueError(f"refresh must be in (0, {MAX_REFRESH}] s, got {refresh}")
        if method not in ("POST", "PUT"):
            raise ValueError(f"method must be POST or PUT, got {method!r}")
        self.client = RestClient(base_url, timeout=timeout, sid=sid)
        self.clock = clock or WallClock()
        self.refresh, self.deadman, self.method = refresh, deadman, method
        self.laser_mount = laser_mount
        self.camera_extrinsics = camera_extrinsics or CameraExtrinsics()
        self.camera_hfov = camera_hfov
        self.posts = 0
        self.post_errors = 0
        self.deadman_stops = 0
        self._lock = threading.Lock()
        self._wake = threading.Event()
        self._stop = threading.Event()
        self._command = (0.0, 0.0, 0.0)
        self._command_time = -math.inf
        self._closed = False
        try:
            self.client.get_json("/data/odometry")
        except RestError as exc:
            raise BackendUnavailable(f"Robotino REST API not reachable: {exc}") from None
        self._parts = self._gripper = None
        try:
            self._compose()
        except BaseException:
            self._closed = True
            raise
        self._thread = threading.Thread(target=self._run, name="robotino-rest-drive", daemon=True)
        self._thread.start()

    def _compose(self) -> None:
        cfg = self.config
        if cfg is None:
            return
        if cfg.gripper:
            from backends.robotino.gripper import ArduinoGripper
            self._gripper = ArduinoGripper(cfg.gripper["device"], clock=self.clock).open()
        if cfg.laser or cfg.camera:
            from backends.robotino.parts import SensorParts
            try:
                self._parts = SensorParts(cfg, self.clock).start()
            except BaseException:
                if self._gripper is not None:
                    self._gripper.close()
                raise

    @property
    def capabilities(self) -> Capability:
        caps = (Capability.DRIVE | Capability.ODOMETRY | Capability.BUMPER | Capability.LASER
                | Capability.CAMERA)
        return caps | Capability.GRIPPER if self._gripper is not None else caps

    @property
    def parts(self):
        return self._parts

    def _need_gripper(self):
        if self._gripper is None:
            raise CapabilityError(f"{self.name}: no gripper (configure one in the robot config)")
        return self._gripper

    def gripper_open(self) -> None:
        self._need_gripper().open_gripper()

    def gripper_close(self) -> None:
        self._need_gripper().close_gripper()

    def gripper_move(self, x: float, y: float, z: float) -> None:
        self._need_gripper().move(x, y, z)

    def gripper_status(self):
        return self._need_gripper().status()

    def holding(self) -> bool | None:
        return None

    # -- motion ---------------------------------------------------------------
    def drive(self, vx: float, vy: float, omega: float) -> None:
        values = (float(vx), float(vy), float(omega))
        if not all(math.isfinite(v) for v in values):
            raise BackendError(f"velocity must be finite, got {values}")
        if self._closed:
            raise BackendError("robotino_rest backend is closed")
        if self._parts is not None and any(values):
            lost = self._parts.lost()
            if lost is not None:
                self.stop()
                raise lost
        with self._lock:
            self._command = values
            self._command_time = self.clock.now()
        self._wake.set()

    def stop(self) -> None:
        with self._lock:
            self._command = (0.0, 0.0, 0.0)
        self._wake.set()
        self._post((0.0, 0.0, 0.0))

    def _post(self, command) -> bool:
        try:
            self.client.send_json(OMNIDRIVE, list(command), self.method)
        except RestError as exc:
            self.post_errors += 1
            if self.post_errors in (1, 10, 100) or self.post_errors % 1000 == 0:
                log.warning("omnidrive failed (%d so far): %s", self.post_errors, exc)
            return False
        self.posts += 1
        return True

    def _run(self) -> None:
        zero_sent = True
        while not self._stop.is_set():
            due = self.clock.now() + self.refresh      # period from start to start
            with self._lock:
                command, stamp = self._command, self._command_time
                if any(command) and self.clock.now() - stamp >= self.deadman:
                    self._command = command = (0.0, 0.0, 0.0)
                    self.deadman_stops += 1
            if any(command):
                self._post(command)
                zero_sent = False
            elif not zero_sent:
                zero_sent = self._post(command)
            self._wake.wait(max(0.0, due - self.clock.now()))
            self._wake.clear()

    # -- sensors --------------------------------------------------------------
    def _get(self, path: str):
        try:
            return self.client.get_json(path)
        except RestError as exc:
            raise BackendUnavailable(str(exc)) from None

    def odometry(self) -> Odometry:
        v = _numbers(self._get("/data/odometry"), 6, "/data/odometry")
        return Odometry(self.clock.now(), Pose2D(v[0], v[1], wrap_angle(v[2])), v[3], v[4], v[5])

    def bumper(self) -> bool:
        data = self._get("/data/bumper")
        if not isinstance(data, dict) or "value" not in data:
            raise BackendError(f"/data/bumper: expected {{'value': bool}}, got {str(data)[:80]}")
        return bool(data["value"])

    def distance_sensors(self) -> tuple[float, ...]:
        """The nine IR distance sensors (numbers as the API reports them)."""
        return tuple(_numbers(self._get("/data/distancesensorarray"), 9, "/data/distancesensorarray"))

    def laser_scan(self) -> LaserScan | None:
        if self._parts is not None and self._parts.laser is not None:
            return self._parts.laser_scan()
        data = self._get("/data/scan0")
        if not isinstance(data, dict):
            raise BackendError(f"/data/scan0: expected an object, got {str(data)[:80]}")
        ranges = _numbers(data.get("ranges", []), None, "/data/scan0 ranges")
        if not ranges:
            return None
        try:
            angle_min = float(data["angle_min"])
            increment = float(data["angle_increment"])
            rmin, rmax = float(data["range_min"]), float(data["range_max"])
        except (KeyError, TypeError, ValueError) as exc:
            raise BackendError(f"/data/scan0: missing or bad field {exc}") from None
        r = np.asarray(ranges, dtype=float)
        r[~np.isfinite(r) | (r > rmax) | (r < rmin)] = np.inf
        return LaserScan(self.clock.now(), angle_min, increment, rmin, rmax, r, self.laser_mount)

    def camera_image(self, camera: str = "front") -> CameraImage | None:
        if self._parts is not None and self._parts.camera is not None:
            return self._parts.camera_image(camera)
        if camera != "front":
            raise BackendError(f"robotino_rest has one camera ('front'), not {camera!r}")
        import cv2
        try:
            raw = self.client.get_bytes("/cam0")
        except RestError as exc:
            raise BackendUnavailable(str(exc)) from None
        if not raw:
            return None
        image = cv2.imdecode(np.frombuffer(raw, dtype=np.uint8), cv2.IMREAD_COLOR)
        if image is None:
            raise BackendError(f"/cam0: {len(raw)} bytes that are not a decodable image")
        h, w = image.shape[:2]
        return CameraImage(self.clock.now(), image, CameraIntrinsics.from_fov(w, h, self.camera_hfov),
                           self.camera_extrinsics, camera)

    # -- life cycle -------------------------------------------------------------
    def close(self) -> None:
        if self._closed:
            return
        self._closed = True
        with self._lock:
            self._command = (0.0, 0.0, 0.0)
        self._stop.set()
        self._wake.set()
        self._thread.join(timeout=2.0)
        self._post((0.0, 0.0, 0.0))
        if self._parts is not None:
            self._parts.close()
        if self._gripper is not None:
            self._gripper.close()
