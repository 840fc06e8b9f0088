"""What the world's side and the devices' side of an emulated robot share
(:mod:`.hardware`, :mod:`.hardware_process`): the gripper sketch the world's
gripper follows, the forwarding of its commands, the devices' arguments,
configuration and counts, and :class:`CoupledRig`, the world's side of one
robot's devices."""
from __future__ import annotations

import logging
import math
import time

import numpy as np

from backends.robotino.arduino import GripperFirmware
from backends.robotino.firmware import RPM_PER_TICK_PER_MS
from backends.robotino.gripper_protocol import StepsPerMetre
from backends.robotino.kinematics import OmniKinematics
from rll_bt.clock import Clock
from rll_bt.contracts.world import STALE_CAST  # (re-exported: a world this far behind casts nothing)

from . import sensors

log = logging.getLogger(__name__)

#: the gripper API's (x, y, z) = the Arduino's axes (metres) + this origin
GRIPPER_ORIGIN = (0.0, -0.10, 0.0)
HOLDING_SENSOR = "distance:8>1.5"
HOLDING_VOLTS, EMPTY_VOLTS = 2.5, 0.3
#: the base emulator not scheduled for this long (s): its wheels stop, in the emulated firmware (which
#: then stands until the emulator runs again) and in the world at the same moment.  A real base's
#: microcontroller never stalls; an emulator on a loaded machine does, and the world must not drive the
#: robot on at the last wheel speeds meanwhile (the host's odometry, integrated from the speeds it
#: polls, skips gaps of more than a second: the robot ended LOCALISATION_LOST), nor stop the wheels
#: while the firmware reports them turning (the host would count motion the world did not make)
SILENT_STOP = 0.3


#: the longest world step of a process game (games/processes.ProcessGame._tick): a world behind the wall
#: clock steps at most this far at a time, each step followed by a sync
WORLD_STEP = 0.1
#: the wheels' positions kept (one row per base-emulator step, about 5 ms): some 5 s, more than a
#: hardware game's world catches up (ProcessGame.catch_up, 2 s)
TRACK_ROWS = 1024


class WheelTrack:
    """The base firmware's wheel positions (motor ticks) at the base emulator's steps, in a ring
    (``rows``: TRACK_ROWS x 4 floats, time and three positions; ``count``: one float, rows written):
    how fast the wheels turned on average over a stretch of the wall clock.  A world behind the wall
    clock steps over time gone by: driven by the wheels' speeds of now, a robot that stopped or set off
    meanwhile moved in the world otherwise than its odometry counted (in a seed-1 game at 420fc1f on a
    machine whose load left the world's process a quarter of a core, the robots were lost most of the
    game); driven by the speeds of then, it moves as the odometry says."""

    def __init__(self, rows: np.ndarray | None = None, count: np.ndarray | None = None):
        self.rows = np.zeros((TRACK_ROWS, 4)) if rows is None else rows
        self.count = np.zeros(1) if count is None else count

    def add(self, t: float, positions) -> None:
        n = int(self.count[0])
        self.rows[n % len(self.rows)] = (t, *positions)
        self.count[0] = n + 1

    def copy(self) -> WheelTrack:
        return WheelTrack(self.rows.copy(), self.count.copy())

    def mean_rpm(self, a: float, b: float) -> list[float] | None:
        """The wheels' mean speeds (rpm) from wall time ``a`` to ``b`` (to the last row when ``b`` is
        later); None when the rows do not cover ``a`` or the stretch is shorter than a millisecond."""
        n, size = int(self.count[0]), len(self.rows)
        k = min(n, size)
        if k < 2:
            return None
        rows = self.rows[np.arange(n - k, n) % size]
        t = rows[:, 0]
        b = min(b, float(t[-1]))
        if a < t[0] or b - a < 1e-3:
            return None
        pa = [float(np.interp(a, t, rows[:, 1 + i])) for i in range(3)]
        pb = [float(np.interp(b, t, rows[:, 1 + i])) for i in range(3)]
        return [(q - p) * RPM_PER_TICK_PER_MS / ((b - a) * 1000.0) for p, q in zip(pa, pb)]


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


def build_devices(spec: dict, *, clock: Clock, laser_source, frame_source, link_dir: str | None = None,
                  laser_wake=None):
    """(:class:`~backends.robotino.rig.EmulatedRobot`, its :class:`WorldGripperFirmware`), not started;
    the laser sends a scan when ``laser_wake`` (a :class:`~backends.devices.laser.source.CastSignal`)
    says the world cast its ranges."""
    from backends.robotino.emulator import RobotinoEmulator
    from backends.robotino.rig import EmulatedRobot
    fw = WorldGripperFirmware()
    emu = RobotinoEmulator(gripper=True, link_dir=link_dir, clock=clock, gripper_firmware=fw,
                           stall_stop=SILENT_STOP)
    rig = EmulatedRobot(**spec, emulator=emu, link_dir=emu.link_dir, clock=clock, laser_source=laser_source,
                        frame_source=frame_source, laser_wake=laser_wake)
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
            "emulator_stalls": s["emulator_stalls"], "longest_stall_s": s["longest_stall_s"],
            "stall_stops": s["stall_stops"]}


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
        self.robot.follows_wheels = True        # the firmware's wheels are the robot's motion, ramped already
        self.kinematics = OmniKinematics()
        self.gripper = GripperLink(self.robot)
        self.angles = angles
        self.scan_period = scan_period
        self.camera_period = 1.0 / camera_fps if camera_fps > 0 else math.inf
        self._next_scan = self._next_frame = -math.inf
        self.scans = self.frames = 0
        self.silent_stops = 0           # times the world stopped turning wheels for a stalled base emulator
        self._silent = False

    def wall(self) -> float:
        """The devices' clock (the machine's monotonic clock)."""
        return time.monotonic()

    def sync(self, world_time: float, at: float | None = None) -> None:
        """After a world step to ``world_time``, which stands for wall time ``at`` (default: now)."""
        r = self.robot
        rpm, stepped = self._exchange(world_time)
        past = None
        if at is not None and self.wall() - at > 0.01:
            # behind the wall clock: the next step covers wall time gone by, at the wheels' speeds of then
            past = self._wheels(at, min(at + WORLD_STEP, self.wall()))
        if past is not None:
            rpm = past
            self._silent = False
        elif stepped is not None and self.wall() - stepped > SILENT_STOP:
            # the base emulator has not run for SILENT_STOP: its firmware stops the wheels at that
            # moment when it runs again (RobotinoEmulator.stall_stop), so the world stops them now
            if any(rpm) and not self._silent:
                self.silent_stops += 1
            self._silent = True
            rpm = [0.0, 0.0, 0.0]
        else:
            self._silent = False
        vx, vy, w = self.kinematics.inverse(*rpm)
        r.drive(vx, vy, w, world_time)
        if at is not None and self.wall() - at > STALE_CAST:
            return      # catching up: a cast or a render of a world this far behind is stale before it is sent
        # the world as it stands is of this time on the devices' clock (now, or the wall time a world
        # behind it stands at): a scan says so in its stamp (laser/source.py), a frame in its X-Timestamp
        cast = self.wall() if at is None else min(at, self.wall())
        if world_time >= self._next_scan:
            self._next_scan = max(self._next_scan + self.scan_period, world_time)
            self._put_ranges(sensors.laser_ranges(self.world.cid, r, self.angles, noisy=True) * 1000.0, cast)
            self.scans += 1
        if world_time >= self._next_frame and self._camera_wanted():
            self._next_frame = max(self._next_frame + self.camera_period, world_time)
            self._put_image(self.world.camera_image(r).image, cast)
            self.frames += 1

    def holding_volts(self) -> float:
        return HOLDING_VOLTS if self.robot.holding is not None else EMPTY_VOLTS

    def _exchange(self, world_time: float) -> tuple[list[float], float | None]:
        """Hand the devices what the world has for them; the wheels' speeds (rpm) and the
        time of the base emulator's step they are of (None: not stepped yet)."""
        raise NotImplementedError

    def _wheels(self, a: float, b: float) -> list[float] | None:
        """The wheels' mean speeds (rpm) from wall time ``a`` to ``b`` (:class:`WheelTrack`), or None."""
        raise NotImplementedError

    def _put_ranges(self, ranges_mm: np.ndarray, cast: float) -> None:
        """The laser's newest ranges (mm), cast at ``cast`` (:meth:`wall`); the laser is told at once."""
        raise NotImplementedError

    def _camera_wanted(self) -> bool:
        raise NotImplementedError

    def _put_image(self, image: np.ndarray, taken: float) -> None:
        """The camera's newest frame, rendered of the world at ``taken`` (:meth:`wall`)."""
        raise NotImplementedError


