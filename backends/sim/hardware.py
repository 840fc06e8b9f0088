"""Emulated hardware fed by the PyBullet world: each simulated robot as the
devices a real Robotino has, speaking their real protocols.

    hw = WorldHardware(world, laser="urg").start()
    rig = hw.add(("CYAN", 1))           # the robot must be in the world
    backend = open_backend("robotino", robot_config=rig.config())   # in an agent
    ...                                  # the world's owner, after every world.step():
    hw.sync()

Per robot (:class:`WorldRig`, on an :class:`~backends.robotino.rig.EmulatedRobot`):

* the base firmware on a pty: the wheels' actual speeds (what the firmware's
  motor loop makes of the host's set-points) drive the robot in the world,
  which moves it (and stops it at obstacles); the host integrates its own
  odometry from the measured wheel speeds, as on the real robot;
* the laser (URG on a pty, TiM on a TCP port): the ranges are the world's
  ray casts (:func:`backends.sim.sensors.laser_ranges`, the robot's laser
  noise included) for the device's own beam angles from the robot's laser
  mount, taken every scan period; the device sends them at once
  (:class:`~backends.devices.laser.source.CastSignal`), stamped with the
  moment they were cast;
* the camera (MJPEG over HTTP): the frames the world renders from the
  robot's camera (:meth:`World.camera_image`), at ``camera_fps``;
* the gripper Arduino on a pty: its commanded axis targets and finger state
  drive the world's gripper; the axis positions and its moving/idle state
  it reports are the world gripper's; whether a workpiece is held reaches
  the host through IR distance sensor 8 of the base (the configuration's
  ``holding_sensor: distance:8>1.5``), as a team wires a sensor into the jaws.

Everything the world does happens in :meth:`WorldHardware.sync`, on the
thread that steps the world (PyBullet is not thread-safe); the device
threads only read what it stored.  Device time is the wall clock.
"""
from __future__ import annotations

import math
import threading

import numpy as np

from backends.devices.laser.source import CastSignal
from rll_bt.clock import Clock, WallClock

from .hardware_parts import CoupledRig, WheelTrack, build_devices, device_spec, device_stats, rig_config


class WorldRig(CoupledRig):
    """One robot's devices as threads of the world's process (see the module
    doc); :class:`~.hardware_process.ProcessRig` puts them in a process of their own."""

    def __init__(self, world, key: tuple[str, int], *, laser: str = "urg", laser_model: str | None = None,
                 camera_fps: float = 5.0, clock: Clock | None = None, link_dir: str | None = None):
        self.clock = clock or WallClock()
        spec = device_spec(world.robots[key], key, laser=laser, laser_model=laser_model, camera_fps=camera_fps)
        self._cast_signal = CastSignal()
        self.rig, self.gripper_fw = build_devices(spec, clock=self.clock, laser_source=self._laser_source,
                                                  frame_source=self._frame, link_dir=link_dir,
                                                  laser_wake=self._cast_signal)
        dev = self.rig.laser_device
        super().__init__(world, key, self.rig.laser_angles(), dev.model.scan_period if dev else math.inf, camera_fps)
        self._lock = threading.Lock()
        self._ranges_mm: np.ndarray | None = None
        self._cast = math.nan
        self._image = None
        self._image_seq = 0
        self._image_sent = -1
        self._track = WheelTrack()
        self.rig.base.on_step = self._record        # called by the emulator's thread, under its lock

    def _record(self, now: float) -> None:
        self._track.add(now, [m.position for m in self.rig.base.firmware.motors[:3]])

    def _wheels(self, a: float, b: float) -> list[float] | None:
        with self.rig.base.lock:
            return self._track.mean_rpm(a, b)

    def start(self) -> WorldRig:
        self.rig.start()
        return self

    def stop(self) -> None:
        self.rig.stop()
        self._cast_signal.close()

    def stats(self) -> dict:
        return {**device_stats(self.rig), "scans_computed": self.scans, "frames_rendered": self.frames,
                "silent_stops": self.silent_stops}

    # -- what the device threads read ---------------------------------------------------
    def _laser_source(self, t: float):
        with self._lock:
            if self._ranges_mm is None:                 # nothing cast yet
                return np.full(len(self.angles), np.nan), -math.inf
            # the ranges and the device time they were cast at (the scan's stamp)
            return self._ranges_mm, self._cast - self.rig.laser_device.boot

    def _frame(self):
        with self._lock:
            if self._image is None or self._image_seq == self._image_sent:
                return None
            self._image_sent = self._image_seq
            return self._image

    def config(self, **faults) -> dict:
        """The robot configuration (:func:`rig_config`)."""
        return rig_config(self.rig, **faults)

    # -- the world's side -----------------------------------------------------------------
    def wall(self) -> float:
        return self.clock.now()

    def _exchange(self, world_time: float) -> tuple[list[float], float | None]:
        emu = self.rig.base
        with emu.lock:
            fw = emu.firmware
            # the wheels as the emulator's own thread last advanced them (advancing the firmware
            # here, before that thread has read what the host sent, would trip its watchdog)
            rpm = [m.ss for m in fw.motors[:3]]
            stepped = emu.last_step
            fw.distance[8] = self.holding_volts()
            self._sync_gripper(world_time)
        return rpm, stepped

    def _put_ranges(self, ranges_mm: np.ndarray, cast: float) -> None:
        with self._lock:
            self._ranges_mm, self._cast = ranges_mm, cast
        self._cast_signal.notify()

    def _camera_wanted(self) -> bool:
        return self.rig.camera_server is not None and self.rig.camera_server.clients > 0

    def _put_image(self, image: np.ndarray, taken: float) -> None:
        with self._lock:
            self._image = (image, taken)
            self._image_seq += 1

    def _sync_gripper(self, world_time: float) -> None:
        fw = self.gripper_fw
        fw.world_busy, fw.world_position = self.gripper.forward(fw.moves, fw.is_open, fw.target, world_time)
        fw.pending = False
        if not fw.moves:          # the axes were only homed: the sketch's targets are where the world's gripper is
            fw.target = list(fw.world_position)


class WorldHardware:
    """Every robot's rig; :meth:`sync` after each world step.  ``devices``:
    "threads" (:class:`WorldRig`, the devices in this process) or "process"
    (:class:`~.hardware_process.ProcessRig`, each robot's devices in a process
    of their own, as a real robot's are on microcontrollers and sensors no
    interpreter lock of the world's holds up)."""

    def __init__(self, world, *, laser: str = "urg", laser_model: str | None = None, camera_fps: float = 5.0,
                 clock: Clock | None = None, devices: str = "threads"):
        if devices not in ("threads", "process"):
            raise ValueError(f"devices must be 'threads' or 'process', not {devices!r}")
        self.world = world
        self.laser = laser
        self.laser_model = laser_model
        self.camera_fps = camera_fps
        self.devices = devices
        self.clock = clock or WallClock()
        self.rigs: dict[tuple[str, int], CoupledRig] = {}

    def add(self, key: tuple[str, int]) -> CoupledRig:
        if self.devices == "process":
            from .hardware_process import ProcessRig
            rig = ProcessRig(self.world, key, laser=self.laser, laser_model=self.laser_model,
                             camera_fps=self.camera_fps)
        else:
            rig = WorldRig(self.world, key, laser=self.laser, laser_model=self.laser_model,
                           camera_fps=self.camera_fps, clock=self.clock).start()
        self.rigs[key] = rig
        return rig

    def sync(self, at: float | None = None) -> None:
        """After a world step; ``at``: the wall time the world stands at, when it is behind the wall
        clock (a laser cast is stamped with it), else now."""
        t = self.world.time
        for rig in self.rigs.values():
            rig.sync(t, at)

    def stats(self) -> dict:
        return {f"{team}/{n}": rig.stats() for (team, n), rig in self.rigs.items()}

    def stop(self) -> None:
        for rig in self.rigs.values():
            rig.stop()
        self.rigs.clear()
