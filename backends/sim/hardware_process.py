"""One robot's emulated devices in a process of their own, fed by the world.

    hw = WorldHardware(world, laser="urg", devices="process")
    rig = hw.add(("CYAN", 1))           # starts the devices' process; rig.config() as with threads

A real Robotino's base firmware, gripper Arduino and laser run on their own
microcontrollers: nothing the robot's computer does holds them up.  In the
world's process the emulators are threads that share one interpreter lock
with PyBullet, whose camera renders and ray casts hold it for tens of
milliseconds at a time; on a loaded machine the emulators then went seconds
without reading their ptys (the host's writes timed out, the laser stream
stopped, the base's watchdog stopped the robot), which a real robot never
sees.  Here the base firmware, the gripper sketch, the laser and the camera
server of one robot run in a child process; the world's process and it
share one block of memory (:class:`_Shared`):

* world -> devices: the laser's ranges (mm), when they were cast and their
  sequence number (and a :class:`~backends.devices.laser.source.CastSignal`
  that wakes the laser's thread to send them at once), the
  camera's last frame and its number, the holding sensor's volts, the world
  gripper's axes (in the sketch's steps), whether it is busy, and the last
  sketch command it has taken;
* devices -> world: the three wheels' actual speeds (rpm) and the time of
  the base emulator's step they are of (a base emulator that has not run for
  :data:`~.hardware_parts.SILENT_STOP` has its wheels stopped in the world,
  as its firmware stops them at that moment when it runs again), the gripper
  sketch's moves, finger state, axis targets and command count, and how many
  clients watch the camera.

The base emulator's thread copies between the block and the firmware objects
at the end of each of its steps (:attr:`RobotinoEmulator.on_step`: when the
host's frames or its own timers wake it, no polling of its own); the world's
process only reads and writes the block (:meth:`ProcessRig.sync`).  Commands (the configuration,
counts, a pulled cable, stop) go over a pipe.  The child exits when the
world's process goes away.
"""
from __future__ import annotations

import logging
import math
import multiprocessing as mp

import numpy as np

from backends.devices.laser.source import CastSignal

from .hardware_parts import TRACK_ROWS, CoupledRig, WheelTrack, device_spec

log = logging.getLogger(__name__)

MAX_BEAMS = 2048
# float slots of the shared block
RANGES_SEQ, IMAGE_SEQ, HOLDING, G_BUSY, G_POS, G_ACK = 0, 1, 2, 3, 4, 7
RPM, G_MOVES, G_OPEN, G_TARGET, G_COMMANDS, CLIENTS, IMAGE_H, IMAGE_W = 8, 11, 12, 13, 16, 17, 18, 19
STEPPED = 20           # the base emulator's step the wheels' speeds are of (time.monotonic(); nan: none yet)
RANGES_CAST = 21       # when the world cast the laser's ranges (time.monotonic(): the scan's stamp)
TRACK_COUNT = 22      # rows written to the wheel track (hardware_parts.WheelTrack)
IMAGE_TAKEN = 23      # the world time the camera's frame is of (time.monotonic(): its X-Timestamp)
HEADER = 24
BEAMS = HEADER         # the laser's ranges (mm) from here
TRACK = HEADER + MAX_BEAMS     # the wheel track's rows (time, three positions) from here


class _Shared:
    """The block both processes see: ``floats`` (header + ranges), ``image``
    (bytes of the newest frame), ``lock`` around every read and write."""

    def __init__(self, ctx, image_bytes: int):
        self.floats = ctx.RawArray("d", TRACK + 4 * TRACK_ROWS)
        self.image = ctx.RawArray("B", image_bytes)
        self.lock = ctx.Lock()
        self.floats[G_POS] = math.nan
        self.floats[STEPPED] = math.nan

    def view(self) -> tuple[np.ndarray, np.ndarray]:
        return np.frombuffer(self.floats, dtype=np.float64), np.frombuffer(self.image, dtype=np.uint8)

    def track(self) -> WheelTrack:
        """The wheel track in the block (read and written under :attr:`lock`)."""
        f = np.frombuffer(self.floats, dtype=np.float64)
        return WheelTrack(f[TRACK:].reshape(TRACK_ROWS, 4), f[TRACK_COUNT:TRACK_COUNT + 1])


class ProcessRig(CoupledRig):
    """The world's side of a robot whose devices run in a child process."""

    def __init__(self, world, key: tuple[str, int], *, laser: str = "urg", laser_model: str | None = None,
                 camera_fps: float = 5.0, start_timeout: float = 180.0):
        robot = world.robots[key]
        spec = device_spec(robot, key, laser=laser, laser_model=laser_model, camera_fps=camera_fps)
        ctx = mp.get_context("spawn")
        h, w = robot.config.camera_height, robot.config.camera_width
        self._shared = _Shared(ctx, h * w * 3)
        self._floats, self._image = self._shared.view()
        self._track = self._shared.track()
        self._conn, child = ctx.Pipe()
        self._cast_signal = CastSignal()          # the world's casts wake the child's laser
        self._proc = ctx.Process(target=serve, args=(spec, self._shared, child, self._cast_signal), daemon=True,
                                 name=f"devices-{key[0].lower()}-{key[1]}")
        self._proc.start()
        child.close()
        if not self._conn.poll(start_timeout):
            self._proc.kill()
            raise RuntimeError(f"the devices of {key[0]} {key[1]} did not start within {start_timeout:g} s")
        ready = self._conn.recv()
        if "error" in ready:
            self._proc.join(5.0)
            raise RuntimeError(f"the devices of {key[0]} {key[1]} failed to start: {ready['error']}")
        super().__init__(world, key, np.asarray(ready["angles"]), ready["scan_period"], camera_fps)
        self._config = ready["config"]
        self._ranges_seq = 0
        self._image_seq = 0
        self._final_stats: dict | None = None

    @property
    def pid(self) -> int:
        """The devices' process."""
        return self._proc.pid

    # -- commands to the child ---------------------------------------------------------------
    def _ask(self, *request, timeout: float = 10.0):
        self._conn.send(request)
        if not self._conn.poll(timeout):
            raise RuntimeError(f"the devices' process did not answer {request[0]!r} within {timeout:g} s")
        answer = self._conn.recv()
        if isinstance(answer, dict) and "error" in answer:
            raise ValueError(answer["error"])
        return answer

    def config(self, **faults) -> dict:
        """The robot configuration (:func:`~.hardware.rig_config`) of the child's devices."""
        return self._ask("config", faults) if faults else dict(self._config)

    def unplug(self, device: str, seconds: float) -> None:
        self._ask("unplug", device, seconds)

    def set_silent(self, device: str, silent: bool) -> None:
        self._ask("set_silent", device, silent)

    def stats(self) -> dict:
        s = self._final_stats if self._final_stats is not None else self._ask("stats")
        return {**s, "scans_computed": self.scans, "frames_rendered": self.frames, "silent_stops": self.silent_stops}

    def stop(self) -> None:
        if self._proc.is_alive():
            try:
                self._final_stats = self._ask("stop")
            except (OSError, EOFError, RuntimeError) as exc:
                log.warning("%s %s: the devices' process did not stop cleanly: %s", *self.key, exc)
            self._proc.join(5.0)
            if self._proc.is_alive():
                self._proc.kill()
                self._proc.join(2.0)
        self._conn.close()
        self._cast_signal.close()

    # -- the world's side -----------------------------------------------------------------------
    def _exchange(self, world_time: float) -> tuple[list[float], float | None]:
        f = self._floats
        with self._shared.lock:
            rpm = [float(v) for v in f[RPM:RPM + 3]]
            stepped = None if math.isnan(f[STEPPED]) else float(f[STEPPED])
            moves, is_open = int(f[G_MOVES]), bool(f[G_OPEN])
            target = [float(v) for v in f[G_TARGET:G_TARGET + 3]]
            commands = f[G_COMMANDS]
        busy, position = self.gripper.forward(moves, is_open, target, world_time)
        with self._shared.lock:
            f[HOLDING] = self.holding_volts()
            f[G_BUSY] = 1.0 if busy else 0.0
            f[G_POS:G_POS + 3] = position
            f[G_ACK] = commands
        return rpm, stepped

    def _wheels(self, a: float, b: float) -> list[float] | None:
        with self._shared.lock:
            track = self._track.copy()
        return track.mean_rpm(a, b)

    def _put_ranges(self, ranges_mm: np.ndarray, cast: float) -> None:
        n = len(ranges_mm)
        with self._shared.lock:
            self._floats[BEAMS:BEAMS + n] = ranges_mm
            self._floats[RANGES_CAST] = cast
            self._ranges_seq += 1
            self._floats[RANGES_SEQ] = self._ranges_seq
        self._cast_signal.notify()

    def _camera_wanted(self) -> bool:
        return self._floats[CLIENTS] > 0

    def _put_image(self, image: np.ndarray, taken: float) -> None:
        flat = np.ascontiguousarray(image, dtype=np.uint8).reshape(-1)
        if flat.size > self._image.size:
            raise ValueError(f"a {image.shape} frame does not fit the {self._image.size} bytes shared")
        with self._shared.lock:
            self._image[:flat.size] = flat
            self._floats[IMAGE_H], self._floats[IMAGE_W] = image.shape[0], image.shape[1]
            self._floats[IMAGE_TAKEN] = taken
            self._image_seq += 1
            self._floats[IMAGE_SEQ] = self._image_seq


# -- the child ----------------------------------------------------------------------------------
class _Devices:
    """The child's side: the devices, their sources on the shared block, and
    the copy between the block and the firmware objects."""

    def __init__(self, spec: dict, shared: _Shared, cast_signal=None):
        from rll_bt.clock import WallClock

        from .hardware_parts import build_devices
        self.shared = shared
        self.floats, self.image = shared.view()
        self.track = shared.track()
        self.rig, self.gripper_fw = build_devices(spec, clock=WallClock(), laser_source=self._laser_source,
                                                  frame_source=self._frame, laser_wake=cast_signal)
        self.beams = len(self.rig.laser_angles()) if self.rig.laser_device is not None else 0
        if self.beams > MAX_BEAMS:
            raise ValueError(f"{self.beams} beams: at most {MAX_BEAMS} are shared")
        self._frame_sent = 0
        self.rig.base.on_step = self.copy

    def _laser_source(self, t: float):
        with self.shared.lock:
            if self.floats[RANGES_SEQ] == 0:              # nothing cast yet
                return np.full(self.beams, np.nan), -math.inf
            cast = float(self.floats[RANGES_CAST]) - self.rig.laser_device.boot
            return self.floats[BEAMS:BEAMS + self.beams].copy(), cast

    def _frame(self):
        with self.shared.lock:
            seq = self.floats[IMAGE_SEQ]
            if seq == 0 or seq == self._frame_sent:
                return None
            self._frame_sent = seq
            h, w = int(self.floats[IMAGE_H]), int(self.floats[IMAGE_W])
            return self.image[:h * w * 3].reshape(h, w, 3).copy(), float(self.floats[IMAGE_TAKEN])

    def copy(self, now: float) -> None:
        """Wheels (as of the base emulator's step at ``now``), gripper sketch and camera
        clients out; holding and the world gripper in."""
        emu, fw, f = self.rig.base, self.gripper_fw, self.floats
        cam = self.rig.camera_server
        with emu.lock:
            rpm = [m.ss for m in emu.firmware.motors[:3]]
            positions = [m.position for m in emu.firmware.motors[:3]]
            with self.shared.lock:
                f[RPM:RPM + 3] = rpm
                f[STEPPED] = now
                self.track.add(now, positions)
                f[G_MOVES], f[G_OPEN], f[G_COMMANDS] = fw.moves, 1.0 if fw.is_open else 0.0, fw.commands
                f[G_TARGET:G_TARGET + 3] = [float(v) for v in fw.target]
                f[CLIENTS] = cam.clients if cam is not None else 0
                holding, busy, ack = f[HOLDING], f[G_BUSY] > 0, f[G_ACK]
                position = None if math.isnan(f[G_POS]) else [float(v) for v in f[G_POS:G_POS + 3]]
            emu.firmware.distance[8] = holding
            fw.pending = fw.commands > ack
            fw.world_busy = busy
            if position is not None:
                fw.world_position = position
                if not fw.moves:      # the axes were only homed: the sketch's targets are where the world's are
                    fw.target = list(position)

    def run(self, conn) -> None:
        from .hardware_parts import device_stats, rig_config
        try:
            while True:
                try:
                    if not conn.poll(0.5):
                        continue
                    request = conn.recv()
                except (EOFError, OSError):          # the world's process is gone
                    return
                what, args = request[0], request[1:]
                try:
                    if what == "stop":
                        conn.send(device_stats(self.rig))
                        return
                    if what == "stats":
                        conn.send(device_stats(self.rig))
                    elif what == "config":
                        conn.send(rig_config(self.rig, **args[0]))
                    elif what == "unplug":
                        self.rig.unplug(*args)
                        conn.send(True)
                    elif what == "set_silent":
                        self.rig.set_silent(*args)
                        conn.send(True)
                    else:
                        conn.send({"error": f"unknown request {what!r}"})
                except (ValueError, AttributeError) as exc:
                    conn.send({"error": str(exc)})
        finally:
            self.rig.stop()


def serve(spec: dict, shared: _Shared, conn, cast_signal=None) -> None:
    """The child process: start the devices, say where they are, serve."""
    from .hardware_parts import rig_config
    logging.basicConfig(level=logging.WARNING, format="%(levelname)s %(name)s: %(message)s")
    try:
        devices = _Devices(spec, shared, cast_signal)
        devices.rig.start()
    except Exception as exc:
        conn.send({"error": f"{type(exc).__name__}: {exc}"})
        return
    dev = devices.rig.laser_device
    conn.send({"angles": devices.rig.laser_angles().tolist() if dev is not None else [],
               "scan_period": dev.model.scan_period if dev is not None else math.inf,
               "config": rig_config(devices.rig)})
    devices.run(conn)
