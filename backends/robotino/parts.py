"""The laser and the camera of a real robot, as a backend composes them.

:class:`SensorParts` builds the drivers a :class:`~.config.RobotConfig`
names (:class:`~backends.devices.laser.urg.UrgLaser` or
:class:`~backends.devices.laser.tim.TimLaser`, and a
:class:`~backends.devices.camera.CameraGrabber`), starts them and waits for
each one's first reading (:class:`BackendUnavailable` naming the device
that gave none), and answers for them: :meth:`laser_scan` and
:meth:`camera_image` return the newest reading or raise
:class:`~rll_bt.backend.SensorLost` when the device stopped delivering
(no reading for ``faults.stale`` / ``faults.camera_stale`` seconds);
:meth:`lost` says which is lost.  Both Robotino backends use it.
"""
from __future__ import annotations

from rll_bt.backend import BackendUnavailable, CameraImage, CapabilityError, LaserScan, SensorLost
from rll_bt.clock import Clock

from .config import RobotConfig


def make_laser(cfg: RobotConfig, clock: Clock):
    spec = cfg.laser
    common = {"mount": cfg.laser_mount(), "clock": clock}
    if "timeout" in spec:
        common["timeout"] = float(spec["timeout"])
    if spec["type"] == "urg":
        from backends.devices.laser.urg import UrgLaser
        device = spec.get("device") or f"socket://{spec['host']}:{spec.get('port', 10940)}"
        return UrgLaser(device, mode=spec.get("mode", "stream"), encoding=spec.get("encoding", 3), **common)
    from backends.devices.laser.tim import TimLaser
    return TimLaser(spec["host"], spec.get("port", 2112), mode=spec.get("mode", "stream"),
                    dialect=spec.get("dialect", "a"), **common)


def make_camera(cfg: RobotConfig, clock: Clock):
    import math

    from backends.devices.camera import CameraGrabber, load_intrinsics
    spec = cfg.camera
    intr = load_intrinsics(cfg.resolve(spec["calibration"])) if spec.get("calibration") else None
    source = spec["source"]
    if isinstance(source, str) and "://" not in source and not source.startswith("/dev/") and not source.isdigit():
        source = cfg.resolve(source)
    return CameraGrabber(source, intrinsics=intr, extrinsics=cfg.camera_extrinsics(), clock=clock,
                         hfov=math.radians(spec.get("hfov", 60.0)), timeout=float(spec.get("timeout", 1.0)),
                         latency=float(spec.get("latency", 0.0)),
                         size=tuple(spec["size"]) if spec.get("size") else None)


class SensorParts:
    def __init__(self, cfg: RobotConfig, clock: Clock):
        self.config = cfg
        self.clock = clock
        self.laser = make_laser(cfg, clock) if cfg.laser else None
        self.camera = make_camera(cfg, clock) if cfg.camera else None

    def start(self) -> SensorParts:
        """Start every device and wait for its first reading."""
        wait = self.config.startup_wait
        try:
            for dev in (self.laser, self.camera):
                if dev is not None:
                    dev.start()
            for dev in (self.laser, self.camera):
                if dev is None:
                    continue
                end = self.clock.now() + wait
                while dev.latest() is None and self.clock.now() < end:
                    self.clock.sleep(0.01)
                if dev.latest() is None:
                    last = dev.stats().last_error or "nothing arrived"
                    raise BackendUnavailable(f"{dev.describe()}: no reading within {wait:g} s ({last})")
        except BaseException:
            self.close()
            raise
        return self

    def close(self) -> None:
        for dev in (self.laser, self.camera):
            if dev is not None:
                dev.close()

    def lost(self) -> SensorLost | None:
        """The first device that stopped delivering, as the error to raise."""
        if self.laser is not None and not self.laser.healthy(self.config.stale):
            s = self.laser.stats()
            why = "its link is down" if not s.connected else f"no scan for more than {self.config.stale:g} s"
            return SensorLost("laser", f"laser lost: {self.laser.describe()}: {why}"
                                       + (f" ({s.last_error})" if s.last_error else ""))
        if self.camera is not None and not self.camera.healthy(self.config.camera_stale):
            s = self.camera.stats()
            why = "it is closed" if not s.connected else f"no frame for more than {self.config.camera_stale:g} s"
            return SensorLost("camera", f"camera lost: {self.camera.describe()}: {why}")
        return None

    def laser_scan(self) -> LaserScan | None:
        if self.laser is None:
            raise CapabilityError("no laser configured")
        if not self.laser.healthy(self.config.stale):
            raise self.lost() or SensorLost("laser", "laser lost")
        return self.laser.latest()

    def camera_image(self, camera: str = "front") -> CameraImage | None:
        if self.camera is None:
            raise CapabilityError("no camera configured")
        if camera != self.camera.name:
            raise CapabilityError(f"no camera {camera!r} (only {self.camera.name!r})")
        if not self.camera.healthy(self.config.camera_stale):
            raise SensorLost("camera", f"camera lost: {self.camera.describe()}")
        return self.camera.latest()
