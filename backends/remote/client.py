"""The calling end: a :class:`~rll_bt.backend.Backend` whose robot lives in
another process (see :mod:`backends.remote`)."""
from __future__ import annotations

from rll_bt.backend import Backend, BackendError, BackendUnavailable, Capability, Odometry
from rll_bt.clock import Clock, WallClock
from rll_bt.comm.jsonlink import FramedClient, LinkClosed, parse_address

from .codec import ERRORS, decode


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

    @staticmethod
    def serve(resolve, now, host: str = "127.0.0.1", port: int = 0):
        """The serving end for a process that holds robots: a
        :class:`~backends.remote.server.BackendServer` answering for
        ``resolve(team, number)`` (a :class:`~rll_bt.backend.Backend`), its
        replies stamped with ``now()``.  Games reach it through the entry
        point, never by importing this package."""
        from .server import BackendServer
        return BackendServer(resolve, now, host, port)

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
