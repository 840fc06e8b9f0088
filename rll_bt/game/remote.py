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

The framing is shared with other links of a ``--processes`` game (the
simulator's station link between the world and the refbox):
:class:`FramedServer` serves requests from the owner's loop and may push
frames of its own (without an ``id``) to its clients, never blocking on a
slow reader (what a client does not take yet waits in that client's
buffer); :class:`FramedClient` calls and waits for the reply of its
request's ``id``, keeping pushed frames in order for :meth:`FramedClient.pushed`.
"""
from __future__ import annotations

import base64
import json
import selectors
import socket
import struct
from collections import deque
from collections.abc import Callable

import numpy as np

from ..backend import (
    Backend,
    BackendError,
    BackendUnavailable,
    Battery,
    CameraExtrinsics,
    CameraImage,
    CameraIntrinsics,
    Capability,
    CapabilityError,
    Detections,
    GripperState,
    GripperStatus,
    LaserScan,
    LightDetection,
    Odometry,
    Pose2D,
    TagDetection,
)
from ..clock import Clock, WallClock

_LEN = struct.Struct(">I")
MAX_MESSAGE = 16 << 20
MAX_BUFFERED = 64 << 20          # bytes waiting for a client that reads nothing: then it is dropped
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


# -- framing ----------------------------------------------------------------------------------------------
def frame(obj) -> bytes:
    """``obj`` as one frame: 4-byte big-endian length, UTF-8 JSON."""
    body = json.dumps(obj, separators=(",", ":"), allow_nan=True).encode("utf-8")
    return _LEN.pack(len(body)) + body


class LinkClosed(ConnectionError):
    """The other end closed the link (its process ended) or it broke."""


class FrameReader:
    """Bytes in, whole frame bodies out (ValueError on a frame over :data:`MAX_MESSAGE`)."""

    def __init__(self) -> None:
        self._buf = bytearray()

    def feed(self, data: bytes) -> list[bytes]:
        buf = self._buf
        buf += data
        out = []
        while len(buf) >= _LEN.size:
            (size,) = _LEN.unpack_from(buf)
            if size > MAX_MESSAGE:
                raise ValueError(f"a frame of {size} bytes (at most {MAX_MESSAGE})")
            if len(buf) < _LEN.size + size:
                break
            out.append(bytes(buf[_LEN.size:_LEN.size + size]))
            del buf[:_LEN.size + size]
        return out


def parse_address(address: str, what: str = "address") -> tuple[str, int]:
    """``"HOST:PORT"`` -> (host, port); ValueError naming ``what`` otherwise."""
    host, sep, port = str(address).rpartition(":")
    try:
        p = int(port)
    except ValueError:
        p = -1
    if not sep or not 0 < p < 65536:
        raise ValueError(f"{what} must be HOST:PORT, not {address!r}")
    return host or "127.0.0.1", p


class FramedClient:
    """The calling end of a framed link to ``host:port``.  :meth:`call`
    sends a request with a fresh ``id`` and waits (``timeout`` s at most,
    then :class:`TimeoutError`) for the reply with that ``id``; frames
    without an ``id`` that arrive meanwhile (pushed by the server) are kept
    in order for :meth:`pushed`.  A closed link raises :class:`LinkClosed`;
    connecting may raise any :class:`OSError`."""

    def __init__(self, host: str, port: int, timeout: float = 5.0):
        self.timeout = timeout
        self._sock = socket.create_connection((host, port), timeout=timeout)
        self._sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        self._sock.settimeout(timeout)
        self._reader = FrameReader()
        self._frames: deque[dict] = deque()
        self._pushed: list[dict] = []
        self._ids = 0
        self.closed = False

    def call(self, request: dict) -> dict:
        self._ids += 1
        rid = self._ids
        self._check()
        try:
            self._sock.sendall(frame({**request, "id": rid}))
        except OSError as exc:
            raise self._lost(exc) from None
        while True:
            while not self._frames:
                self._read(block=True)
            msg = self._frames.popleft()
            if "id" not in msg:
                self._pushed.append(msg)
            elif msg["id"] == rid:
                return msg

    def pushed(self) -> list[dict]:
        """What the server pushed, in order, taking whatever has arrived (never waits)."""
        self._check()
        self._read(block=False)
        while self._frames:
            msg = self._frames.popleft()
            if "id" not in msg:
                self._pushed.append(msg)
        out, self._pushed = self._pushed, []
        return out

    def _read(self, block: bool) -> None:
        while True:
            try:
                if block:
                    data = self._sock.recv(1 << 16)
                else:
                    self._sock.setblocking(False)
                    try:
                        data = self._sock.recv(1 << 16)
                    finally:
                        self._sock.settimeout(self.timeout)
            except (BlockingIOError, InterruptedError):
                return
            except TimeoutError:
                raise
            except OSError as exc:
                raise self._lost(exc) from None
            if not data:
                raise self._lost(None)
            for body in self._reader.feed(data):
                self._frames.append(json.loads(body))
            if block:
                return

    def _lost(self, exc) -> LinkClosed:
        self.close()
        return LinkClosed("the other end closed the link" if exc is None else f"the link broke: {exc}")

    def _check(self) -> None:
        if self.closed:
            raise LinkClosed("the link is closed")

    def close(self) -> None:
        if not self.closed:
            self.closed = True
            try:
                self._sock.close()
            except OSError:
                pass


class FramedServer:
    """The serving end of framed links on ``host:port`` (0: ephemeral, see
    :attr:`port`), driven by its owner's loop: :meth:`poll` accepts,
    answers every whole request that arrived (:meth:`answer`, in order per
    client) and sends what waits.  Nothing here blocks on a client: what a
    slow client has not taken waits in its buffer (a client that lets more
    than :data:`MAX_BUFFERED` bytes pile up is dropped)."""

    def __init__(self, host: str = "127.0.0.1", port: int = 0):
        self._sel = selectors.DefaultSelector()
        self._listen = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
        self._listen.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        self._listen.bind((host, port))
        self._listen.listen(16)
        self._listen.setblocking(False)
        self.port = self._listen.getsockname()[1]
        self._sel.register(self._listen, selectors.EVENT_READ, None)
        self._readers: dict[socket.socket, FrameReader] = {}
        self._out: dict[socket.socket, bytearray] = {}

    # -- what a subclass provides ----------------------------------------------------------------
    def answer(self, conn: socket.socket, body: bytes) -> dict | None:
        """The reply to one request (None: no reply)."""
        raise NotImplementedError

    def connected(self, conn: socket.socket) -> None:
        """A client connected."""

    # -- serving ----------------------------------------------------------------------------------
    @property
    def clients(self) -> list[socket.socket]:
        return list(self._readers)

    @property
    def unsent(self) -> int:
        """Bytes waiting for clients that have not taken them yet."""
        return sum(len(out) for out in self._out.values())

    def poll(self, timeout: float) -> int:
        """Serve whatever arrives within ``timeout`` seconds; returns the requests answered."""
        served = 0
        for key, events in self._sel.select(max(timeout, 0.0)):
            sock = key.fileobj
            if sock is self._listen:
                self._accept()
                continue
            if events & selectors.EVENT_WRITE and sock in self._out:
                self._flush(sock)
            if events & selectors.EVENT_READ and sock in self._readers:
                served += self._read(sock)
        return served

    def send(self, conn: socket.socket, obj) -> None:
        """Queue ``obj`` for ``conn`` and send what the socket takes now."""
        out = self._out.get(conn)
        if out is None:
            return
        out += frame(obj)
        self._flush(conn)

    def push(self, obj) -> int:
        """Send ``obj`` to every client; returns how many."""
        clients = self.clients
        for conn in clients:
            self.send(conn, obj)
        return len(clients)

    def _accept(self) -> None:
        try:
            conn, _addr = self._listen.accept()
        except OSError:
            return
        conn.setblocking(False)
        conn.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        self._readers[conn] = FrameReader()
        self._out[conn] = bytearray()
        self._sel.register(conn, selectors.EVENT_READ, None)
        self.connected(conn)

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
        try:
            bodies = self._readers[conn].feed(data)
        except ValueError:
            self._drop(conn)
            return 0
        served = 0
        for body in bodies:
            reply = self.answer(conn, body)
            served += 1
            if reply is not None:
                self.send(conn, reply)
            if conn not in self._readers:
                break
        return served

    def _flush(self, conn: socket.socket) -> None:
        out = self._out[conn]
        while out:
            try:
                n = conn.send(out)
            except (BlockingIOError, InterruptedError):
                break
            except OSError:
                self._drop(conn)
                return
            del out[:n]
        if len(out) > MAX_BUFFERED:
            self._drop(conn)
            return
        want = selectors.EVENT_READ | (selectors.EVENT_WRITE if out else 0)
        if self._sel.get_key(conn).events != want:
            self._sel.modify(conn, want)

    def _drop(self, conn: socket.socket) -> None:
        try:
            self._sel.unregister(conn)
        except (KeyError, ValueError):
            pass
        self._readers.pop(conn, None)
        self._out.pop(conn, None)
        try:
            conn.close()
        except OSError:
            pass

    def close(self) -> None:
        for conn in list(self._readers):
            self._drop(conn)
        try:
            self._sel.unregister(self._listen)
        except (KeyError, ValueError):
            pass
        self._listen.close()
        self._sel.close()


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
        try:
            host, port = parse_address(address)
        except ValueError as exc:
            raise BackendUnavailable(f"remote backend: {exc}") from None
        try:
            self._link = FramedClient(host, port, timeout)
        except OSError as exc:
            raise BackendUnavailable(f"remote backend: cannot reach {host}:{port}: {exc}") from None
        self._shift: float | None = None
        self._caps = self._call("capabilities")

    def _call(self, method: str, *args):
        if self._link.closed:
            raise BackendUnavailable("remote backend: closed")
        try:
            reply = self._link.call({"robot": self.robot, "m": method, "a": list(args)})
        except LinkClosed:
            raise BackendUnavailable("remote backend: the world closed the connection") from None
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
        self._link.close()


# -- the server -------------------------------------------------------------------------------------------
class BackendServer(FramedServer):
    """Serves backends by (team, number) on ``host:port`` (0: ephemeral, see :attr:`port`)."""

    def __init__(self, resolve: Callable[[str, int], Backend], now: Callable[[], float],
                 host: str = "127.0.0.1", port: int = 0):
        super().__init__(host, port)
        self.resolve = resolve
        self.now = now
        self.calls = 0

    def poll(self, timeout: float) -> int:
        served = super().poll(timeout)
        self.calls += served
        return served

    def answer(self, conn, body: bytes) -> dict:
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
        except Exception as exc:
            return {"id": rid, "e": "BackendError", "msg": f"{type(exc).__name__}: {exc}"}


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
