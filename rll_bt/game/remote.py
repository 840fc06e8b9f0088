"""A robot backend over TCP: the world process serves, an agent process calls.

Entry point ``rll_bt.backends: remote`` -> :class:`RemoteBackend`::

    rll-bt agent --backend remote --backend-opt address=127.0.0.1:4470 --backend-opt robot=2 ...

Wire: each message is a 4-byte big-endian length and a UTF-8 JSON object.
A request ``{"id", "robot": [team, number], "m": method, "a": [args]}`` gets
``{"id", "r": result, "now": server time}`` or ``{"id", "e": error class
name, "msg": text}``.  Results are plain JSON (laser ranges and camera
images as base64 of little-endian float32 / uint8 arrays).  Stamps are
moved onto the client's clock: the offset between the server's time and the
client's ``clock.now()`` is taken at the first reply.

:class:`BackendServer` answers for any :class:`~rll_bt.backend.Backend`
objects (``resolve(team, number)``); :meth:`BackendServer.poll` serves
what arrived and returns, so the world's loop stays in charge of time.
"""
from __future__ import annotations

import base64
import json
import selectors
import socket
import struct
from typing import Callable

import numpy as np

from ..backend import (Backend, BackendError, BackendUnavailable, Battery, CameraExtrinsics, CameraImage,
                       CameraIntrinsics, Capability, CapabilityError, Detections, GripperState,
                       GripperStatus, LaserScan, LightDetection, Odometry, Pose2D, TagDetection)
from ..clock import Clock, WallClock

_LEN = struct.Struct(">I")
MAX_MESSAGE = 16 << 20
METHODS = ("capabilities", "drive", "stop", "odometry", "laser_scan", "camera_image", "detections",
           "bumper", "battery", "gripper_open", "gripper_close", "gripper_move", "gripper_status")
ERRORS = {"CapabilityError": CapabilityError, "BackendUnavailable": BackendUnavailable,
          "BackendError": BackendError}


def _b64(arr: np.ndarray) -> str:
    return base64.b64encode(np.ascontiguousarray(arr).tobytes()).decode("ascii")


def _pose(p: Pose2D) -> list[float]:
    return [p.x, p.y, p.theta]


# -- values to JSON and back ----------------------------------------------------------------------
def encode(value):
    if value is None or isinstance(value, (bool, int, float, str)):
        return value
    if isinstance(value, Capability):
        return int(value.value)
    if isinstance(value, Odometry):
        return {"stamp": value.stamp, "pose": _pose(value.pose), "v": [value.vx, value.vy, value.omega]}
    if isinstance(value, LaserScan):
        return {"stamp": value.stamp, "angle_min": value.angle_min, "angle_increment": value.angle_increment,
                "range_min": value.range_min, "range_max": value.range_max,
                "ranges": _b64(np.asarray(value.ranges, dtype="<f4")), "mount": _pose(value.mount)}
    if isinstance(value, Detections):
        return {"stamp": value.stamp, "extrinsics": _extr(value.extrinsics),
                "tags": [{"tag_id": t.tag_id, "tvec": list(t.tvec), "rvec": list(t.rvec),
                          "corners": [list(c) for c in t.corners], "camera": t.camera} for t in value.tags],
                "lights": [{"box": list(lt.box), "state": lt.state, "score": lt.score,
                            "probabilities": list(lt.probabilities), "camera": lt.camera, "tag_id": lt.tag_id}
                           for lt in value.lights]}
    if isinstance(value, GripperStatus):
        return {"state": value.state.value, "is_open": value.is_open, "position": list(value.position),
                "holding": value.holding, "message": value.message}
    if isinstance(value, Battery):
        return {"voltage": value.voltage, "current": value.current, "soc": value.soc,
                "external_power": value.external_power}
    if isinstance(value, CameraImage):
        i = value.intrinsics
        return {"stamp": value.stamp, "shape": list(value.image.shape), "data": _b64(value.image.astype(np.uint8)),
                "intrinsics": [i.width, i.height, i.fx, i.fy, i.cx, i.cy, list(i.distortion)],
                "extrinsics": _extr(value.extrinsics), "camera": value.camera}
    raise TypeError(f"cannot send a {type(value).__name__} over the remote backend")


def _extr(e: CameraExtrinsics) -> dict:
    return {"position": list(e.position), "yaw": e.yaw, "pitch": e.pitch}


def _unextr(d: dict) -> CameraExtrinsics:
    return CameraExtrinsics(tuple(d["position"]), d["yaw"], d["pitch"])


def decode(method: str, r, shift: float = 0.0):
    """A result of ``method`` back into the backend's types; stamps + ``shift``."""
    if r is None or method not in ("capabilities", "odometry", "laser_scan", "detections", "gripper_status",
                                   "battery", "camera_image"):
        return r
    if method == "capabilities":
        return Capability(r)
    if method == "odometry":
        return Odometry(r["stamp"] + shift, Pose2D(*r["pose"]), *r["v"])
    if method == "laser_scan":
        ranges = np.frombuffer(base64.b64decode(r["ranges"]), dtype="<f4").astype(np.float64)
        return LaserScan(r["stamp"] + shift, r["angle_min"], r["angle_increment"], r["range_min"],
                         r["range_max"], ranges, Pose2D(*r["mount"]))
    if method == "detections":
        tags = tuple(TagDetection(t["tag_id"], tuple(t["tvec"]), tuple(t["rvec"]),
                                  tuple(tuple(c) for c in t["corners"]), t["camera"]) for t in r["tags"])
        lights = tuple(LightDetection(tuple(lt["box"]), lt["state"], lt["score"], tuple(lt["probabilities"]),
                                      lt["camera"], lt["tag_id"]) for lt in r["lights"])
        return Detections(r["stamp"] + shift, tags, lights, _unextr(r["extrinsics"]))
    if method == "gripper_status":
        return GripperStatus(GripperState(r["state"]), r["is_open"], tuple(r["position"]), r["holding"],
                             r["message"])
    if method == "battery":
        return Battery(**r)
    w, h, fx, fy, cx, cy, dist = r["intrinsics"]
    img = np.frombuffer(base64.b64decode(r["data"]), dtype=np.uint8).reshape(r["shape"])
    return CameraImage(r["stamp"] + shift, img.copy(), CameraIntrinsics(w, h, fx, fy, cx, cy, tuple(dist)),
                       _unextr(r["extrinsics"]), r["camera"])


def _frame(obj) -> bytes:
    body = json.dumps(obj, separators=(",", ":"), allow_nan=True).encode("utf-8")
    return _LEN.pack(len(body)) + body


def _parse_address(address: str) -> tuple[str, int]:
    host, sep, port = str(address).rpartition(":")
    try:
        p = int(port)
    except ValueError:
        p = -1
    if not sep or not 0 < p < 65536:
        raise BackendUnavailable(f"remote backend: address must be HOST:PORT, not {address!r}")
    return host or "127.0.0.1", p


# -- the client ------------------------------------------------------------------------------------------
class RemoteBackend(Backend):
    """Robot ``robot`` (a number, or ``"TEAM/N"``) of the world served at
    ``address`` ("HOST:PORT").  ``timeout``: seconds a call may take before
    :class:`BackendUnavailable`.  ``team`` defaults to CYAN."""

    name = "remote"

    def __init__(self, address: str, robot=1, team: str = "CYAN", timeout: float = 5.0,
                 clock: Clock | None = None, **_ignored):
        if isinstance(robot, str) and "/" in robot:
            team, robot = robot.split("/", 1)
        self.robot = [str(team).upper(), int(robot)]
        self.clock = clock or WallClock()
        host, port = _parse_address(address)
        try:
            self._sock = socket.create_connection((host, port), timeout=timeout)
        except OSError as exc:
            raise BackendUnavailable(f"remote backend: cannot reach {host}:{port}: {exc}") from None
        self._sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        self._sock.settimeout(timeout)
        self._ids = 0
        self._shift: float | None = None
        self._closed = False
        self._caps = self._call("capabilities")

    def _recv_exact(self, n: int) -> bytes:
        buf = bytearray()
        while len(buf) < n:
            chunk = self._sock.recv(n - len(buf))
            if not chunk:
                raise BackendUnavailable("remote backend: the world closed the connection")
            buf += chunk
        return bytes(buf)

    def _call(self, method: str, *args):
        if self._closed:
            raise BackendUnavailable("remote backend: closed")
        self._ids += 1
        try:
            self._sock.sendall(_frame({"id": self._ids, "robot": self.robot, "m": method, "a": list(args)}))
            (size,) = _LEN.unpack(self._recv_exact(_LEN.size))
            reply = json.loads(self._recv_exact(size))
        except (OSError, ValueError) as exc:
            raise BackendUnavailable(f"remote backend: {method} failed: {exc}") from None
        if "e" in reply:
            raise ERRORS.get(reply["e"], BackendError)(reply.get("msg", reply["e"]))
        if self._shift is None and "now" in reply:
            self._shift = self.clock.now() - float(reply["now"])
        return decode(method, reply.get("r"), self._shift or 0.0)

    @property
    def capabilities(self) -> Capability:
        return self._caps

    def drive(self, vx: float, vy: float, omega: float) -> None:
        self._call("drive", float(vx), float(vy), float(omega))

    def stop(self) -> None:
        self._call("stop")

    def odometry(self) -> Odometry:
        return self._call("odometry")

    def laser_scan(self):
        return self._call("laser_scan")

    def camera_image(self, camera: str = "front"):
        return self._call("camera_image", camera)

    def detections(self, camera: str = "front"):
        return self._call("detections", camera)

    def bumper(self) -> bool:
        return bool(self._call("bumper"))

    def battery(self):
        return self._call("battery")

    def gripper_open(self) -> None:
        self._call("gripper_open")

    def gripper_close(self) -> None:
        self._call("gripper_close")

    def gripper_move(self, x: float, y: float, z: float) -> None:
        self._call("gripper_move", float(x), float(y), float(z))

    def gripper_status(self):
        return self._call("gripper_status")

    def close(self) -> None:
        if not self._closed:
            self._closed = True
            try:
                self._sock.close()
            except OSError:
                pass


# -- the server -------------------------------------------------------------------------------------------
class BackendServer:
    """Serves backends by (team, number) on ``host:port`` (0: ephemeral, see :attr:`port`)."""

    def __init__(self, resolve: Callable[[str, int], Backend], now: Callable[[], float],
                 host: str = "127.0.0.1", port: int = 0):
        self.resolve = resolve
        self.now = now
        self._sel = selectors.DefaultSelector()
        self._listen = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
        self._listen.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        self._listen.bind((host, port))
        self._listen.listen(16)
        self._listen.setblocking(False)
        self.port = self._listen.getsockname()[1]
        self._sel.register(self._listen, selectors.EVENT_READ, None)
        self._bufs: dict[socket.socket, bytearray] = {}
        self.calls = 0

    def poll(self, timeout: float) -> int:
        """Serve whatever arrives within ``timeout`` seconds; returns calls answered."""
        served = 0
        for key, _ in self._sel.select(max(timeout, 0.0)):
            sock = key.fileobj
            if sock is self._listen:
                try:
                    conn, _addr = self._listen.accept()
                except OSError:
                    continue
                conn.setblocking(False)
                conn.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
                self._bufs[conn] = bytearray()
                self._sel.register(conn, selectors.EVENT_READ, None)
                continue
            served += self._read(sock)
        self.calls += served
        return served

    def _read(self, conn: socket.socket) -> int:
        try:
            data = conn.recv(1 << 16)
        except (BlockingIOError, InterruptedError):
            return 0
        except OSError:
            data = b""
        if not data:
            self._drop(conn)
            return 0
        buf = self._bufs[conn]
        buf += data
        served = 0
        while len(buf) >= _LEN.size:
            (size,) = _LEN.unpack_from(buf)
            if size > MAX_MESSAGE:
                self._drop(conn)
                return served
            if len(buf) < _LEN.size + size:
                break
            body = bytes(buf[_LEN.size:_LEN.size + size])
            del buf[:_LEN.size + size]
            reply = self._answer(body)
            try:
                conn.setblocking(True)
                conn.sendall(_frame(reply))
                conn.setblocking(False)
            except OSError:
                self._drop(conn)
                return served
            served += 1
        return served

    def _answer(self, body: bytes) -> dict:
        try:
            req = json.loads(body)
            rid = req.get("id")
        except ValueError as exc:
            return {"id": None, "e": "BackendError", "msg": f"bad request: {exc}"}
        method = req.get("m")
        if method not in METHODS:
            return {"id": rid, "e": "BackendError", "msg": f"unknown method {method!r}"}
        try:
            team, number = req.get("robot", ["CYAN", 1])
            backend = self.resolve(str(team), int(number))
            target = getattr(backend, method)
            value = target if method == "capabilities" else target(*req.get("a", []))
            return {"id": rid, "r": encode(value), "now": self.now()}
        except (CapabilityError, BackendUnavailable, BackendError) as exc:
            return {"id": rid, "e": type(exc).__name__ if type(exc).__name__ in ERRORS else "BackendError",
                    "msg": str(exc)}
        except Exception as exc:  # noqa: BLE001 - a bad call must not take the world down
            return {"id": rid, "e": "BackendError", "msg": f"{type(exc).__name__}: {exc}"}

    def _drop(self, conn: socket.socket) -> None:
        try:
            self._sel.unregister(conn)
        except (KeyError, ValueError):
            pass
        self._bufs.pop(conn, None)
        try:
            conn.close()
        except OSError:
            pass

    def close(self) -> None:
        for conn in list(self._bufs):
            self._drop(conn)
        try:
            self._sel.unregister(self._listen)
        except (KeyError, ValueError):
            pass
        self._listen.close()
        self._sel.close()


def free_ports(count: int, tcp: bool = False, host: str = "127.0.0.1") -> list[int]:
    """``count`` distinct UDP (or TCP) ports the system has free right now (bound and released)."""
    socks, ports = [], []
    try:
        for _ in range(count):
            s = socket.socket(socket.AF_INET, socket.SOCK_STREAM if tcp else socket.SOCK_DGRAM)
            s.bind((host, 0))
            socks.append(s)
            ports.append(s.getsockname()[1])
    finally:
        for s in socks:
            s.close()
    return ports

