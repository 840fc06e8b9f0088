"""Does a backend keep the contract of :class:`~rll_bt.backend.Backend`?

In the spirit of Gymnasium's ``check_env``: one call exercises everything a
tree, a skill or an agent relies on, and says what is wrong::

    from rll_bt.backend import check_backend
    report = check_backend(robot)                       # BackendContractError lists every problem
    report = check_backend(robot, advance=time.sleep)   # also: driving moves it, stop() stops it

What is checked:

- :attr:`~Backend.capabilities` is a :class:`Capability`;
- every capability the backend advertises works: each of its methods
  (:data:`METHODS`) returns, and readings have the documented types and
  shapes with plausible values in SI units (metres, radians, seconds, volts;
  a range in millimetres or an angle in degrees is caught);
- every capability it does not advertise raises :class:`CapabilityError`
  from each of its methods;
- reading stamps never go back, and all readings share one time base;
- :meth:`~Backend.stop` returns and is safe twice;
- with ``advance`` (a callable letting that many seconds of the backend's
  time pass: ``time.sleep`` for a real or emulated robot, a world's step for
  a simulated one): a drive command moves the odometry and :meth:`stop`
  brings the velocity back to zero (within ``wait`` seconds, at least 0.5); a sensor that answers None ("nothing
  yet") must deliver within ``wait`` seconds;
- leaving ``with backend:`` stops the robot (:meth:`stop` or
  ``drive(0, 0, 0)``) and closes it; :meth:`close` is safe twice.

The check ends by leaving the backend's context, so the backend is closed
afterwards.  ``move=False`` keeps the robot still (no drive or gripper
commands but zero velocity) for a robot that must not move.
"""
from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field
from numbers import Integral, Real

import numpy as np

from .interface import Backend, Capability, CapabilityError
from .types import (
    Battery,
    CameraExtrinsics,
    CameraImage,
    CameraIntrinsics,
    Detections,
    GripperState,
    GripperStatus,
    LaserScan,
    LightDetection,
    Odometry,
    Pose2D,
    TagDetection,
)

#: the methods each capability stands for (a capability added to the enum must be added here;
#: a test holds the two together)
METHODS: dict[str, tuple[str, ...]] = {
    "DRIVE": ("drive", "stop"),
    "ODOMETRY": ("odometry",),
    "LASER": ("laser_scan",),
    "CAMERA": ("camera_image",),
    "GRIPPER": ("gripper_status", "gripper_move", "gripper_open", "gripper_close"),
    "BUMPER": ("bumper",),
    "BATTERY": ("battery",),
    "DETECTIONS": ("detections",),
}

# plausibility bounds (SI units)
MAX_SPEED = 5.0            # m/s
MAX_TURN = 20.0            # rad/s
MAX_FIELD = 1000.0         # m from the odometry origin
MAX_LASER_RANGE = 100.0    # m (a range in millimetres is far beyond)
MAX_MOUNT = 3.0            # m from the robot's centre (laser, camera, gripper axes)
MAX_TAG_DISTANCE = 30.0    # m
MAX_VOLTAGE = 100.0        # V (a voltage in millivolts is far beyond)
STAMP_SPREAD = 60.0        # s the stamps of two readings taken together may lie apart


class BackendContractError(AssertionError):
    """The backend breaks its contract; :attr:`problems` says how, one line each."""

    def __init__(self, name: str, problems: list[str]):
        self.problems = list(problems)
        super().__init__(f"backend {name!r} breaks the backend contract:\n" + "\n".join(f"- {p}" for p in problems))


@dataclass
class BackendCheck:
    """What :func:`check_backend` found: the backend's ``name`` and
    ``capabilities``, ``checked`` (what it exercised, in order) and
    ``problems`` (empty when the contract holds)."""

    name: str
    capabilities: object = None
    checked: list[str] = field(default_factory=list)
    problems: list[str] = field(default_factory=list)

    @property
    def ok(self) -> bool:
        return not self.problems


def _number(x) -> bool:
    return isinstance(x, Real) and not isinstance(x, bool) and math.isfinite(float(x))


class _Checker:
    def __init__(self, backend, *, advance: Callable[[float], None] | None, wait: float, move: bool,
                 cameras: tuple[str, ...]):
        self.b = backend
        self.Capability = Capability
        self.advance, self.wait, self.move, self.cameras = advance, wait, move, cameras
        self.report = BackendCheck(getattr(backend, "name", type(backend).__name__))
        self.last_stamp: dict[str, float] = {}

    # -- bookkeeping -------------------------------------------------------------------------------
    def problem(self, text: str) -> None:
        self.report.problems.append(text)

    def note(self, what: str) -> None:
        if what not in self.report.checked:
            self.report.checked.append(what)

    def call(self, what: str, fn, *args):
        """``fn(*args)``; (True, result), or (False, None) with the exception noted as a problem."""
        self.note(what)
        try:
            return True, fn(*args)
        except CapabilityError as exc:
            self.problem(f"{what}: advertised but raised CapabilityError ({exc})")
        except Exception as exc:
            self.problem(f"{what}: raised {type(exc).__name__}: {exc}")
        return False, None

    def expect(self, ok: bool, text: str) -> bool:
        if not ok:
            self.problem(text)
        return ok

    def numbers(self, what: str, values, n: int | None = None, bound: float | None = None) -> bool:
        vals = tuple(values) if isinstance(values, (tuple, list, np.ndarray)) else None
        if vals is None or (n is not None and len(vals) != n) or not all(_number(v) for v in vals):
            return self.expect(False, f"{what}: expected {n or 'some'} finite numbers, got {values!r}")
        if bound is not None and any(abs(float(v)) > bound for v in vals):
            return self.expect(False, f"{what}: {values!r} is implausible (beyond {bound:g}; wrong units?)")
        return True

    def stamp(self, what: str, stamp) -> None:
        if not self.expect(_number(stamp), f"{what}.stamp: expected finite seconds, got {stamp!r}"):
            return
        prev = self.last_stamp.get(what)
        self.expect(prev is None or stamp >= prev, f"{what}.stamp went back in time ({prev} then {stamp})")
        self.last_stamp[what] = float(stamp)

    def one_time_base(self) -> None:
        """Readings are compared with each other (a scan with the odometry of its
        moment): their stamps must share one time base."""
        if len(self.last_stamp) > 1:
            (lo, t0), (hi, t1) = (min(self.last_stamp.items(), key=lambda kv: kv[1]),
                                  max(self.last_stamp.items(), key=lambda kv: kv[1]))
            self.expect(t1 - t0 <= STAMP_SPREAD, f"the stamps of {lo} ({t0:.3f}) and {hi} ({t1:.3f}) are "
                        f"{t1 - t0:.0f} s apart: the readings are not on one time base")

    def pose(self, what: str, p, bound: float) -> bool:
        if not self.expect(isinstance(p, Pose2D), f"{what}: expected a Pose2D, got {type(p).__name__}"):
            return False
        ok = self.numbers(f"{what} (x, y)", (p.x, p.y), 2, bound)
        return self.numbers(f"{what}.theta", (p.theta,), 1, 2 * math.pi + 1e-6) and ok

    def typed(self, what: str, value, kind) -> bool:
        return self.expect(isinstance(value, kind), f"{what}: expected {kind.__name__}, got {type(value).__name__}")

    # -- readings ----------------------------------------------------------------------------------
    def odometry(self, value) -> Odometry | None:
        if not self.typed("odometry()", value, Odometry):
            return None
        self.stamp("odometry()", value.stamp)
        if self.pose("odometry().pose", value.pose, MAX_FIELD):
            self.expect(-math.pi - 1e-6 <= value.pose.theta <= math.pi + 1e-6,
                        f"odometry().pose.theta {value.pose.theta} is not wrapped to [-pi, pi]")
        self.numbers("odometry() (vx, vy)", (value.vx, value.vy), 2, MAX_SPEED)
        self.numbers("odometry().omega", (value.omega,), 1, MAX_TURN)
        return value

    def laser(self, scan) -> None:
        if not self.typed("laser_scan()", scan, LaserScan):
            return
        self.stamp("laser_scan()", scan.stamp)
        ok = self.numbers("laser_scan() (range_min, range_max)", (scan.range_min, scan.range_max), 2, MAX_LASER_RANGE)
        if ok:
            self.expect(0.0 <= scan.range_min < scan.range_max,
                        f"laser_scan(): need 0 <= range_min < range_max, got {scan.range_min}, {scan.range_max}")
        r = scan.ranges
        if not self.expect(isinstance(r, np.ndarray) and r.ndim == 1 and len(r) > 0
                           and np.issubdtype(r.dtype, np.floating),
                           f"laser_scan().ranges: expected a 1-D float array, got {type(r).__name__} "
                           f"{getattr(r, 'shape', '')} {getattr(r, 'dtype', '')}"):
            return
        if self.numbers("laser_scan() (angle_min, angle_increment)", (scan.angle_min, scan.angle_increment), 2,
                        2 * math.pi + 1e-6):
            self.expect(scan.angle_increment != 0.0, "laser_scan().angle_increment is 0")
            self.expect(abs(scan.angle_increment) * (len(r) - 1) <= 2 * math.pi + 1e-6,
                        f"laser_scan(): {len(r)} beams of {scan.angle_increment} span more than a turn "
                        "(degrees, not radians?)")
        finite = r[np.isfinite(r)]
        if ok and len(finite):
            self.expect(bool(np.all(finite >= 0.0)) and bool(np.all(finite <= scan.range_max * 1.001)),
                        f"laser_scan().ranges: finite readings must lie in [0, range_max={scan.range_max}] "
                        f"(got {float(finite.min()):.3f}..{float(finite.max()):.3f}; beyond range_max is inf)")
        self.expect(not bool(np.any(np.isneginf(r))), "laser_scan().ranges: -inf readings")
        self.pose("laser_scan().mount", scan.mount, MAX_MOUNT)

    def extrinsics(self, what: str, e) -> None:
        if self.typed(what, e, CameraExtrinsics):
            self.numbers(f"{what}.position", e.position, 3, MAX_MOUNT)
            self.numbers(f"{what} (yaw, pitch)", (e.yaw, e.pitch), 2, 2 * math.pi + 1e-6)

    def image(self, cam: str, img) -> None:
        what = f"camera_image({cam!r})"
        if not self.typed(what, img, CameraImage):
            return
        self.stamp(what, img.stamp)
        a = img.image
        if not self.expect(isinstance(a, np.ndarray) and a.ndim == 3 and a.shape[2] == 3 and a.dtype == np.uint8
                           and a.shape[0] > 0 and a.shape[1] > 0,
                           f"{what}.image: expected an H x W x 3 uint8 array (BGR), got {type(a).__name__} "
                           f"{getattr(a, 'shape', '')} {getattr(a, 'dtype', '')}"):
            return
        i = img.intrinsics
        if self.typed(f"{what}.intrinsics", i, CameraIntrinsics):
            self.expect((i.width, i.height) == (a.shape[1], a.shape[0]),
                        f"{what}: intrinsics are {i.width} x {i.height}, the image {a.shape[1]} x {a.shape[0]}")
            if self.numbers(f"{what}.intrinsics (fx, fy, cx, cy)", (i.fx, i.fy, i.cx, i.cy), 4):
                self.expect(i.fx > 0 and i.fy > 0 and 0 <= i.cx <= i.width and 0 <= i.cy <= i.height,
                            f"{what}.intrinsics: focal lengths must be > 0 and the centre inside the image")
            self.numbers(f"{what}.intrinsics.distortion", i.distortion)
        self.extrinsics(f"{what}.extrinsics", img.extrinsics)
        self.typed(f"{what}.camera", img.camera, str)

    def detections(self, cam: str, d) -> None:
        what = f"detections({cam!r})"
        if not self.typed(what, d, Detections):
            return
        self.stamp(what, d.stamp)
        self.extrinsics(f"{what}.extrinsics", d.extrinsics)
        for t in d.tags:
            if self.typed(f"{what}.tags[]", t, TagDetection):
                self.expect(isinstance(t.tag_id, Integral), f"{what}: tag_id {t.tag_id!r} is not an int")
                self.numbers(f"{what}: tag {t.tag_id} tvec", t.tvec, 3, MAX_TAG_DISTANCE)
                self.numbers(f"{what}: tag {t.tag_id} rvec", t.rvec, 3, 4 * math.pi)
        for lt in d.lights:
            if self.typed(f"{what}.lights[]", lt, LightDetection):
                self.expect(isinstance(lt.state, Integral) and 0 <= lt.state <= 7,
                            f"{what}: light state {lt.state!r} is not 0..7 (green 1, yellow 2, red 4)")
                self.expect(len(lt.box) == 4 and all(isinstance(v, Integral) for v in lt.box),
                            f"{what}: light box {lt.box!r} is not 4 ints (x, y, w, h)")

    def gripper(self, st) -> GripperStatus | None:
        if not self.typed("gripper_status()", st, GripperStatus):
            return None
        self.typed("gripper_status().state", st.state, GripperState)
        self.typed("gripper_status().is_open", st.is_open, bool)
        self.numbers("gripper_status().position", st.position, 3, MAX_MOUNT)
        self.expect(st.holding is None or isinstance(st.holding, bool),
                    f"gripper_status().holding: expected True, False or None, got {st.holding!r}")
        self.expect(st.sensed is None or isinstance(st.sensed, bool),
                    f"gripper_status().sensed: expected True, False or None, got {st.sensed!r}")
        return st

    def battery(self, bat) -> None:
        if not self.typed("battery()", bat, Battery):
            return
        if self.numbers("battery() (voltage, current)", (bat.voltage, bat.current), 2, MAX_VOLTAGE):
            self.expect(bat.voltage >= 0, f"battery().voltage {bat.voltage} is negative")
        self.expect(bat.soc is None or (_number(bat.soc) and 0.0 <= bat.soc <= 1.0),
                    f"battery().soc: expected None or 0..1, got {bat.soc!r}")
        self.typed("battery().external_power", bat.external_power, bool)

    # -- waiting for a first reading ---------------------------------------------------------------
    def first(self, what: str, fn, *args):
        """A reading that may be None ("nothing yet"): with ``advance``, wait up to ``wait`` s for one."""
        ok, value = self.call(what, fn, *args)
        if not ok or value is not None or self.advance is None:
            return value
        waited = 0.0
        while value is None and waited < self.wait:
            self.advance(0.05)
            waited += 0.05
            ok, value = self.call(what, fn, *args)
            if not ok:
                return None
        self.expect(value is not None, f"{what}: advertised but nothing arrived in {self.wait:g} s")
        return value

    # -- the check ---------------------------------------------------------------------------------
    def run(self) -> BackendCheck:
        C, b = self.Capability, self.b
        ok, caps = self.call("capabilities", lambda: b.capabilities)
        if not ok or not self.typed("capabilities", caps, C):
            return self.report
        self.report.capabilities = caps
        for name in METHODS:
            if not caps & C[name]:
                self.absent(name)
        if caps & C.ODOMETRY:
            ok, odo = self.call("odometry()", b.odometry)
            if ok:
                self.odometry(odo)
        if caps & C.DRIVE:
            self.drive(caps)
        if caps & C.LASER:
            scan = self.first("laser_scan()", b.laser_scan)
            if scan is not None:
                self.laser(scan)
        for cam in self.cameras:
            if caps & C.CAMERA:
                img = self.first(f"camera_image({cam!r})", b.camera_image, cam)
                if img is not None:
                    self.image(cam, img)
            if caps & C.DETECTIONS:
                ok, d = self.call(f"detections({cam!r})", b.detections, cam)
                if ok:
                    self.detections(cam, d)
        if caps & C.BUMPER:
            ok, hit = self.call("bumper()", b.bumper)
            if ok:
                self.typed("bumper()", hit, bool)
        if caps & C.BATTERY:
            ok, bat = self.call("battery()", b.battery)
            if ok:
                self.battery(bat)
        if caps & C.GRIPPER:
            self.grip()
        self.one_time_base()
        self.leave(caps)
        return self.report

    def absent(self, name: str) -> None:
        args = {"drive": (0.0, 0.0, 0.0), "gripper_move": (0.0, 0.0, 0.0)}
        for method in METHODS[name]:
            if method == "stop":
                continue                  # stop() without DRIVE may do nothing; leaving the context catches it
            what = f"{method}() without {name}"
            self.note(what)
            try:
                getattr(self.b, method)(*args.get(method, ()))
            except CapabilityError:
                continue
            except Exception as exc:
                self.problem(f"{what}: raised {type(exc).__name__} ({exc}), not CapabilityError")
                continue
            self.problem(f"{what}: returned instead of raising CapabilityError (advertise {name}, or raise)")

    def drive(self, caps) -> None:
        C, b = self.Capability, self.b
        ok, r = self.call("drive(0, 0, 0)", b.drive, 0.0, 0.0, 0.0)
        self.expect(not ok or r is None, f"drive() returned {r!r}, not None")
        for i in (1, 2):
            ok, r = self.call(f"stop() #{i}", b.stop)
            self.expect(not ok or r is None, f"stop() returned {r!r}, not None")
        if not self.move or self.advance is None or not caps & C.ODOMETRY:
            return
        ok, before = self.call("odometry() before driving", b.odometry)
        if not ok or not isinstance(before, Odometry):
            return
        end, t = 0.6, 0.0
        while t < end:                    # keep the command alive as a tree would
            if not self.call("drive(0.1, 0, 0)", b.drive, 0.1, 0.0, 0.0)[0]:
                return
            self.advance(0.05)
            t += 0.05
        ok, during = self.call("odometry() while driving", b.odometry)
        if ok and self.odometry(during) is not None:
            moved = during.pose.distance_to(before.pose)
            self.expect(moved > 0.01, f"drive(0.1, 0, 0) for {end:g} s moved the odometry {moved:.3f} m")
        self.call("stop() after driving", b.stop)
        waited, limit = 0.0, max(0.5, self.wait)      # a robot on a loaded machine polls its base late
        while True:
            self.advance(0.05)
            waited += 0.05
            ok, after = self.call("odometry() after stop()", b.odometry)
            if not ok or self.odometry(after) is None:
                break
            speed = math.hypot(after.vx, after.vy)
            if (speed < 0.02 and abs(after.omega) < 0.05) or waited >= limit:
                self.expect(speed < 0.02 and abs(after.omega) < 0.05,
                            f"{waited:.1f} s after stop() the odometry still moves ({speed:.3f} m/s, "
                            f"{after.omega:.3f} rad/s)")
                break

    def grip(self) -> None:
        b = self.b
        ok, st = self.call("gripper_status()", b.gripper_status)
        st = self.gripper(st) if ok else None
        ok, held = self.call("holding()", b.holding)
        self.expect(not ok or held is None or isinstance(held, bool),
                    f"holding(): expected a bool or None, got {held!r}")
        if not self.move or st is None:
            return
        for what, fn, args in (("gripper_move(current position)", b.gripper_move, tuple(st.position)),
                               *((("gripper_close()", b.gripper_close, ()), ("gripper_open()", b.gripper_open, ()))
                                 if st.is_open else
                                 (("gripper_open()", b.gripper_open, ()), ("gripper_close()", b.gripper_close, ())))):
            ok, r = self.call(what, fn, *args)
            self.expect(not ok or r is None, f"{what} returned {r!r}, not None")
        ok, st = self.call("gripper_status() after commands", b.gripper_status)
        if ok:
            self.gripper(st)

    def leave(self, caps) -> None:
        """Leave ``with backend:`` and see that it stopped the robot; close twice."""
        b = self.b
        stops: list[str] = []
        real_stop, real_drive = b.stop, b.drive

        def stop():
            stops.append("stop()")
            return real_stop()

        def drive(vx, vy, omega):
            if (vx, vy, omega) == (0.0, 0.0, 0.0):
                stops.append("drive(0, 0, 0)")
            return real_drive(vx, vy, omega)
        self.note("leaving the context")
        b.stop, b.drive = stop, drive                  # noted on the instance: __exit__ calls self.stop()
        try:
            with b as entered:
                self.expect(entered is b, f"__enter__ returned {type(entered).__name__}, not the backend")
                if self.move and caps & self.Capability.DRIVE:
                    real_drive(0.05, 0.0, 0.0)
        except Exception as exc:
            self.problem(f"leaving the context raised {type(exc).__name__}: {exc}")
        finally:
            for attr in ("stop", "drive"):
                b.__dict__.pop(attr, None)
        if caps & self.Capability.DRIVE:
            self.expect(bool(stops), "leaving the context did not stop the robot (no stop() nor drive(0, 0, 0))")
        self.note("close() again")
        try:
            b.close()
        except Exception as exc:
            self.problem(f"close() a second time raised {type(exc).__name__}: {exc}")


def check_backend(backend, *, advance: Callable[[float], None] | None = None, wait: float = 2.0,
                  move: bool = True, cameras: tuple[str, ...] = ("front",)) -> BackendCheck:
    """Check ``backend`` against the backend contract (see the module doc);
    the report, or :class:`BackendContractError` listing every problem.
    ``cameras``: the camera names to read (``CAMERA``, ``DETECTIONS``)."""
    if not isinstance(backend, Backend):
        raise BackendContractError(type(backend).__name__, [f"{type(backend).__name__} is not a Backend"])
    report = _Checker(backend, advance=advance, wait=wait, move=move, cameras=tuple(cameras)).run()
    if report.problems:
        raise BackendContractError(report.name, report.problems)
    return report
