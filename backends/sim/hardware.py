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
  mount, taken every scan period;
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

import logging
import math
import threading

import numpy as np

from backends.robotino.arduino import GripperFirmware
from backends.robotino.gripper_protocol import StepsPerMetre
from backends.robotino.kinematics import OmniKinematics
from rll_bt.clock import Clock, WallClock

from . import sensors

log = logging.getLogger(__name__)

#: the gripper API's (x, y, z) = the Arduino's axes (metres) + this origin
GRIPPER_ORIGIN = (0.0, -0.10, 0.0)
HOLDING_SENSOR = "distance:8>1.5"
HOLDING_VOLTS, EMPTY_VOLTS = 2.5, 0.3


class WorldGripperFirmware(GripperFirmware):
    """The gripper sketch whose axes are the world gripper's: positions and
    moving/idle come from :meth:`follow`, which the rig calls every sync."""

    def __init__(self):
        super().__init__(speed=1e12, home_time=0.0)
        self.pending = False            # a command the world has not taken yet
        self.moves = 0                  # X/Y/Z commands received (homing does not move the world's gripper)
        self.world_busy = False
        self.world_position: list[float] | None = None
        self.commands = 0               # X/Y/Z/O/G commands received (what the world has taken: :class:`GripperLink`)

    def _command(self, cmd, value, out):
        super()._command(cmd, value, out)
        if cmd in "XYZ":
            self.moves += 1
        if cmd in "XYZOG":
            self.pending = True
            self.commands += 1
            if self.status != "E":
                self._set_status("M", out)

    def advance(self, now: float) -> bytes:
        if self._booting_until is not None:
            return super().advance(now)
        out: list[bytes] = []
        self._now = now
        if self.world_position is not None:
            self.position = list(self.world_position)
        busy = self.pending or self.world_busy
        if self.status == "M" and not busy:
            self._homing_until = None
            self._set_status("I", out)
        elif self.status == "M" and now >= self._next_report:
            self._next_report = now + self.moving_report_period
            out.append(self.status_line())
        return b"".join(out)


class GripperLink:
    """What the gripper sketch was told, forwarded to the world's gripper (on
    the thread that steps the world): an axis target once per new move, the
    fingers when they were told to change; the world gripper's axes (in the
    sketch's steps) and whether it is busy come back."""

    def __init__(self, robot):
        self.robot = robot
        self.steps = StepsPerMetre()
        self._forwarded: tuple | None = None

    def forward(self, moves: int, is_open: bool, target_steps, world_time: float) -> tuple[bool, list[float]]:
        g = self.robot.gripper
        ox, oy, oz = GRIPPER_ORIGIN
        tx, ty, tz = self.steps.to_metres(tuple(int(round(v)) for v in target_steps))
        target = (tx + ox, ty + oy, tz + oz)
        want = (moves, bool(is_open))
        if want != self._forwarded:
            old = self._forwarded
            try:
                if moves and (old is None or old[0] != moves):
                    from .gripper import X_RANGE, Y_RANGE, Z_RANGE
                    clamped = tuple(min(max(v, lo), hi) for v, (lo, hi) in zip(target, (X_RANGE, Y_RANGE, Z_RANGE)))
                    g.command("move", clamped, now=world_time)
                if (old is None or old[1] != is_open) and (is_open != g.is_open or g.busy):
                    g.command("open" if is_open else "close", now=world_time)
            except Exception as exc:            # a target the world refuses: the Arduino reports an error
                log.warning("%s: gripper command refused by the world: %s", self.robot.name, exc)
            self._forwarded = want
        px, py, pz = g.position
        return g.busy, [(px - ox) * self.steps.x, (py - oy) * self.steps.y, (pz - oz) * self.steps.z]


def device_spec(robot, key: tuple[str, int], *, laser: str = "urg", laser_model: str | None = None,
                camera_fps: float = 5.0) -> dict:
    """The :class:`~backends.robotino.rig.EmulatedRobot` arguments of a world robot's devices."""
    cfg, g = robot.config, robot.config.geometry
    mx, my, mz = g.laser_mount
    cx, cy, cz = g.camera_mount
    return {"laser": laser, "laser_model": laser_model, "camera": camera_fps > 0, "gripper": True,
            "camera_fps": max(camera_fps, 0.1), "laser_mount": {"x": mx, "y": my, "z": mz, "yaw": 0.0},
            "camera_mount": {"x": cx, "y": cy, "z": cz, "pitch": math.degrees(cfg.camera_pitch)},
            "camera_hfov": math.degrees(cfg.camera_hfov), "holding_sensor": HOLDING_SENSOR, "name": f"R{key[1]}"}


def build_devices(spec: dict, *, clock: Clock, laser_source, frame_source, link_dir: str | None = None):
    """(:class:`~backends.robotino.rig.EmulatedRobot`, its :class:`WorldGripperFirmware`), not started."""
    from backends.robotino.emulator import RobotinoEmulator
    from backends.robotino.rig import EmulatedRobot
    fw = WorldGripperFirmware()
    emu = RobotinoEmulator(gripper=True, link_dir=link_dir, clock=clock, gripper_firmware=fw)
    rig = EmulatedRobot(**spec, emulator=emu, link_dir=emu.link_dir, clock=clock, laser_source=laser_source,
                        frame_source=frame_source)
    return rig, fw


def rig_config(rig, **faults) -> dict:
    """The robot configuration of emulated devices fed by the world.  Fault
    timing is looser than a real robot's (laser 1 s, camera 3 s): the world
    that feeds the devices shares the machine with the agents, and may fall
    behind a moment.  An agent waits up to 30 s for each device's first
    reading (not 5 s): three agents coming up at once on a loaded machine
    had one give up on its camera's first frame and end the game before it began."""
    cfg = rig.config(**{"stale": 1.0, "camera_stale": 3.0, "startup_wait": 30.0, **faults})
    cfg["gripper"]["origin"] = list(GRIPPER_ORIGIN)
    if "camera" in cfg:
        cfg["camera"]["timeout"] = 3.0
    return cfg


def device_stats(rig) -> dict:
    """What the devices of an :class:`~backends.robotino.rig.EmulatedRobot` counted."""
    s = rig.base.stats()
    laser = rig.laser_device
    return {"base_frames": s["frames"], "watchdog_trips": s["watchdog_trips"],
            "watchdog_motion_stops": s["watchdog_motion_stops"], "scans_sent": laser.scans_sent if laser else 0,
            "frames_sent": rig.camera_server.frames_sent if rig.camera_server else 0,
            "emulator_stalls": s["emulator_stalls"], "longest_stall_s": s["longest_stall_s"]}


class CoupledRig:
    """The world's side of one robot's devices: after every world step
    :meth:`sync` drives the robot with the wheel speeds the base firmware
    runs, hands the devices the holding sensor and the gripper, a laser scan
    every scan period and a camera frame every camera period while a client
    watches.  Subclasses say how the devices are reached (:meth:`_exchange`,
    :meth:`_put_ranges`, :meth:`_camera_wanted`, :meth:`_put_image`)."""

    def __init__(self, world, key: tuple[str, int], angles: np.ndarray, scan_period: float, camera_fps: float):
        self.world = world
        self.key = key
        self.robot = world.robots[key]
        self.kinematics = OmniKinematics()
        self.gripper = GripperLink(self.robot)
        self.angles = angles
        self.scan_period = scan_period
        self.camera_period = 1.0 / camera_fps if camera_fps > 0 else math.inf
        self._next_scan = self._next_frame = -math.inf
        self.scans = self.frames = 0

    def sync(self, world_time: float) -> None:
        r = self.robot
        rpm = self._exchange(world_time)
        vx, vy, w = self.kinematics.inverse(*rpm)
        r.drive(vx, vy, w, world_time)
        if world_time >= self._next_scan:
            self._next_scan = max(self._next_scan + self.scan_period, world_time)
            self._put_ranges(sensors.laser_ranges(self.world.cid, r, self.angles, noisy=True) * 1000.0)
            self.scans += 1
        if world_time >= self._next_frame and self._camera_wanted():
            self._next_frame = max(self._next_frame + self.camera_period, world_time)
            self._put_image(self.world.camera_image(r).image)
            self.frames += 1

    def holding_volts(self) -> float:
        return HOLDING_VOLTS if self.robot.holding is not None else EMPTY_VOLTS

    def _exchange(self, world_time: float) -> list[float]:
        """Hand the devices what the world has for them; the wheels' speeds (rpm)."""
        raise NotImplementedError

    def _put_ranges(self, ranges_mm: np.ndarray) -> None:
        raise NotImplementedError

    def _camera_wanted(self) -> bool:
        raise NotImplementedError

    def _put_image(self, image: np.ndarray) -> None:
        raise NotImplementedError


class WorldRig(CoupledRig):
    """One robot's devices as threads of the world's process (see the module
    doc); :class:`~.hardware_process.ProcessRig` puts them in a process of their own."""

    def __init__(self, world, key: tuple[str, int], *, laser: str = "urg", laser_model: str | None = None,
                 camera_fps: float = 5.0, clock: Clock | None = None, link_dir: str | None = None):
        self.clock = clock or WallClock()
        spec = device_spec(world.robots[key], key, laser=laser, laser_model=laser_model, camera_fps=camera_fps)
        self.rig, self.gripper_fw = build_devices(spec, clock=self.clock, laser_source=self._laser_source,
                                                  frame_source=self._frame, link_dir=link_dir)
        dev = self.rig.laser_device
        super().__init__(world, key, self.rig.laser_angles(), dev.model.scan_period if dev else math.inf, camera_fps)
        self._lock = threading.Lock()
        self._ranges_mm: np.ndarray | None = None
        self._image = None
        self._image_seq = 0
        self._image_sent = -1

    def start(self) -> WorldRig:
        self.rig.start()
        return self

    def stop(self) -> None:
        self.rig.stop()

    def stats(self) -> dict:
        return {**device_stats(self.rig), "scans_computed": self.scans, "frames_rendered": self.frames}

    # -- what the device threads read ---------------------------------------------------
    def _laser_source(self, t: float) -> np.ndarray:
        with self._lock:
            if self._ranges_mm is None:
                return np.full(len(self.angles), np.nan)
            return self._ranges_mm

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
    def _exchange(self, world_time: float) -> list[float]:
        emu = self.rig.base
        with emu.lock:
            fw = emu.firmware
            # the wheels as the emulator's own thread last advanced them (advancing the firmware
            # here, before that thread has read what the host sent, would trip its watchdog)
            rpm = [m.ss for m in fw.motors[:3]]
            fw.distance[8] = self.holding_volts()
            self._sync_gripper(world_time)
        return rpm

    def _put_ranges(self, ranges_mm: np.ndarray) -> None:
        with self._lock:
            self._ranges_mm = ranges_mm

    def _camera_wanted(self) -> bool:
        return self.rig.camera_server is not None and self.rig.camera_server.clients > 0

    def _put_image(self, image: np.ndarray) -> None:
        with self._lock:
            self._image = image
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

    def sync(self) -> None:
        t = self.world.time
        for rig in self.rigs.values():
            rig.sync(t)

    def stats(self) -> dict:
        return {f"{team}/{n}": rig.stats() for (team, n), rig in self.rigs.items()}

    def stop(self) -> None:
        for rig in self.rigs.values():
            rig.stop()
        self.rigs.clear()
