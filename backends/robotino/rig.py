"""A whole emulated Robotino: the base firmware and the gripper Arduino
(:class:`~.emulator.RobotinoEmulator`, ptys), a laser (an URG on a pty or a
TiM on a TCP port) and the camera (MJPEG over HTTP), each speaking its real
protocol, and the robot configuration file that points at them.

    rig = EmulatedRobot(laser="urg", camera=True, gripper=True).start()
    backend = open_backend("robotino", robot_config=rig.config())
    rig.unplug("laser", 2.0)          # the cable pulled for 2 s
    rig.stop()

``laser_source(t)`` gives the distances (mm) the laser measures at device
time ``t`` for its own beam angles (``rig.laser_angles()``, radians in the
laser frame), or ``(distances, taken)`` measured at device time ``taken``,
the scan's stamp (:mod:`backends.devices.laser.source`); ``frame_source()``
the BGR image the camera sees; by default a round room of ``room`` metres
radius and a grey test image.  A simulator passes its own
(``backends.sim.hardware``), and with ``laser_wake`` (a
:class:`~backends.devices.laser.source.CastSignal` it notifies when it cast
new ranges) the laser sends each scan right after its ranges were cast,
not when its own clock says a scan is due.
"""
from __future__ import annotations

import os
import shutil
import tempfile
import time
from collections.abc import Callable

import numpy as np

from rll_bt.clock import Clock, WallClock

LASERS = ("urg", "urg-tcp", "tim")      # urg-tcp: an Ethernet URG (UTM-30LX-EW) on a TCP port


class EmulatedRobot:
    def __init__(self, *, laser: str | None = "urg", camera: bool = True, gripper: bool = True,
                 laser_model: str | None = None, laser_source: Callable[[float], np.ndarray] | None = None,
                 frame_source: Callable[[], np.ndarray] | None = None, camera_fps: float = 10.0,
                 laser_mount: dict | None = None, camera_mount: dict | None = None, camera_hfov: float = 60.0,
                 holding_sensor: str | None = None, link_dir: str | None = None, clock: Clock | None = None,
                 emulator=None, room: float = 3.0, name: str = "emulated", laser_wake=None):
        if laser is not None and laser not in LASERS:
            raise ValueError(f"laser must be one of {', '.join(LASERS)} or None, not {laser!r}")
        self.clock = clock or WallClock()
        self.name = name
        self._own_dir = link_dir is None
        self.link_dir = link_dir or tempfile.mkdtemp(prefix="robotino-rig-")
        os.makedirs(self.link_dir, exist_ok=True)
        self.laser_kind = laser
        self.with_camera = camera
        self.laser_mount = laser_mount or {"x": 0.12, "y": 0.0, "z": 0.2, "yaw": 0.0}
        self.camera_mount = camera_mount or {"x": 0.2, "y": 0.0, "z": 0.6, "pitch": 0.0}
        self.camera_hfov = camera_hfov
        self.camera_fps = camera_fps
        self.holding_sensor = holding_sensor
        self.room = room
        if emulator is None:
            from .emulator import RobotinoEmulator
            emulator = RobotinoEmulator(gripper=gripper, link_dir=self.link_dir, clock=self.clock)
        self.base = emulator
        self.laser_device = self.laser_runner = None
        self.camera_server = None
        self._laser_source = laser_source
        self._frame_source = frame_source
        boot = time.monotonic()
        if laser in ("urg", "urg-tcp"):
            from backends.devices.laser.urg_device import MODELS, UrgDevice
            model = MODELS[laser_model or ("URG-04LX" if laser == "urg" else "UTM-30LX")]
            self.laser_device = UrgDevice(model, self._urg_source, start=boot, on_cast=laser_wake is not None)
            if laser == "urg":
                from backends.devices.ptyrunner import PtyRunner
                self.laser_runner = PtyRunner(self.laser_device, os.path.join(self.link_dir, "urg"),
                                              clock=self.clock, wake=laser_wake)
            else:
                from backends.devices.laser.tcp_emulators import UrgTcpEmulator
                self.laser_runner = UrgTcpEmulator(self.laser_device, clock=self.clock, wake=laser_wake)
        elif laser == "tim":
            from backends.devices.laser.tcp_emulators import TimEmulator
            from backends.devices.laser.tim_device import MODELS, TimDevice
            self.laser_device = TimDevice(MODELS[laser_model or "TiM571"], self._tim_source, start=boot,
                                          on_cast=laser_wake is not None)
            self.laser_runner = TimEmulator(self.laser_device, clock=self.clock, wake=laser_wake)
        if camera:
            from backends.devices.camera.mjpeg import MjpegServer
            self.camera_server = MjpegServer(self._frame, fps=camera_fps, clock=self.clock)

    # -- sources -----------------------------------------------------------------
    def laser_angles(self) -> np.ndarray:
        """The laser's beam angles (rad, laser frame) its source is asked for."""
        dev = self.laser_device
        if self.laser_kind in ("urg", "urg-tcp"):
            return dev.model.step_angle(np.arange(dev.model.max_step + 1))
        return dev.model.angles()

    def _room(self, angles: np.ndarray) -> np.ndarray:
        return np.full(len(angles), self.room * 1000.0)

    def _urg_source(self, t: float) -> np.ndarray:
        if self._laser_source is not None:
            return self._laser_source(t)
        return self._room(self.laser_angles())

    _tim_source = _urg_source

    def _frame(self) -> np.ndarray | None:
        if self._frame_source is not None:
            return self._frame_source()
        img = np.full((240, 320, 3), 128, np.uint8)
        img[100:140, 140:180] = (0, 200, 0)
        return img

    # -- life cycle ------------------------------------------------------------------
    def start(self) -> EmulatedRobot:
        self.base.start()
        if self.laser_runner is not None:
            self.laser_runner.start()
        if self.camera_server is not None:
            self.camera_server.start()
        return self

    def stop(self) -> None:
        if self.camera_server is not None:
            self.camera_server.stop()
        if self.laser_runner is not None:
            self.laser_runner.stop()
        self.base.stop()
        if self._own_dir:
            shutil.rmtree(self.link_dir, ignore_errors=True)

    def __enter__(self) -> EmulatedRobot:
        return self.start()

    def __exit__(self, *exc) -> None:
        self.stop()

    # -- faults ----------------------------------------------------------------------
    def unplug(self, device: str, seconds: float) -> None:
        """Pull ``device`` ("laser", "camera", "base", "gripper") for ``seconds``."""
        if device == "laser":
            self.laser_runner.unplug(seconds)
        elif device == "camera":
            self.camera_server.unplug(seconds)
        elif device in ("base", "gripper"):
            self.base.close_port(seconds, which=device)
        else:
            raise ValueError(f"no device {device!r}")

    def set_silent(self, device: str, silent: bool) -> None:
        if device == "laser":
            self.laser_runner.set_silent(silent)
        elif device == "camera":
            self.camera_server.set_silent(silent)
        elif device == "base":
            self.base.set_silent(silent)
        else:
            raise ValueError(f"no device {device!r}")

    # -- the configuration -------------------------------------------------------------
    def config(self, **faults) -> dict:
        """The robot configuration (a dict of the file's content) for these devices."""
        cfg: dict = {"name": self.name, "base": {"type": "robotino3", "device": self.base.device}}
        if self.laser_kind == "urg":
            cfg["laser"] = {"type": "urg", "device": self.laser_runner.link, "mount": dict(self.laser_mount)}
        elif self.laser_kind in ("tim", "urg-tcp"):
            host, port = self.laser_runner.address
            cfg["laser"] = {"type": self.laser_kind[:3], "host": host, "port": port, "mount": dict(self.laser_mount)}
        if self.camera_server is not None:
            cfg["camera"] = {"source": self.camera_server.url, "hfov": self.camera_hfov,
                             "mount": dict(self.camera_mount)}
        if self.base.gripper_device:
            cfg["gripper"] = {"device": self.base.gripper_device}
            if self.holding_sensor:
                cfg["gripper"]["holding_sensor"] = self.holding_sensor
        if faults:
            cfg["faults"] = dict(faults)
        return cfg

    def write_config(self, path: str, **faults) -> str:
        import yaml
        with open(path, "w") as f:
            f.write("# robot configuration of an emulated Robotino (rll-bt robotino emulate)\n")
            yaml.safe_dump(self.config(**faults), f, sort_keys=False)
        return path

