"""A device model behind a TCP port, as an Ethernet sensor looks to its host:
one thread (``select``) serves every client a session of the model.

A session has ``receive(data, now)``, ``take_output() -> bytes`` and
``advance(now)`` (the :class:`~backends.devices.ptyrunner.PtyRunner`
interface); ``session_factory()`` makes one per accepted connection.  A
device that serves one client at a time (``max_clients=1``) closes a further
connection at once.

    server = DeviceServer(device.session, port=0).start()
    server.address        # ("127.0.0.1", port) for the driver

Faults: :meth:`unplug` drops every connection and stops listening for a
while (connects are refused, as with the cable out), :meth:`set_silent`
keeps the connections but sends nothing.  ``wake`` (a
:class:`~backends.devices.laser.source.CastSignal`) wakes the thread when
the source has cast new ranges, so that a device ``on_cast`` sends them at
once.
"""
from __future__ import annotations

import logging
import select
import socket

from rll_bt.clock import Clock

from .pluggable import Pluggable

log = logging.getLogger(__name__)


class DeviceServer(Pluggable):
    name = "device"

    def __init__(self, session_factory, *, host: str = "127.0.0.1", port: int = 0,
                 clock: Clock | None = None, period: float = 0.005, wake=None, max_clients: int | None = None):
        super().__init__(clock)
        self.session_factory = session_factory
        self.max_clients = max_clients
        self.host = host
        self.port = port
        self.period = period
        self.wake = wake
        self.refused = 0
        self._listener: socket.socket | None = None
        self._clients: dict[socket.socket, object] = {}

    @property
    def address(self) -> tuple[str, int]:
        return self.host, self.port

    @property
    def thread_name(self) -> str:
        return f"{self.name}:{self.port}"

    def _listen(self) -> None:
        s = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
        s.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        s.bind((self.host, self.port))
        s.listen(4)
        s.setblocking(False)
        self.port = s.getsockname()[1]
        self._listener = s

    def start(self) -> DeviceServer:
        self._listen()
        self._start_thread()
        return self

    def _close_link(self) -> None:
        self._drop_all()

    @property
    def plugged(self) -> bool:
        return self._listener is not None

    @property
    def clients(self) -> int:
        return len(self._clients)

    def _drop_all(self) -> None:
        for c in list(self._clients):
            self._close(c)
        if self._listener is not None:
            self._listener.close()
            self._listener = None

    def _close(self, c: socket.socket) -> None:
        self._clients.pop(c, None)
        try:
            c.close()
        except OSError:
            pass

    def _step(self) -> None:
        now = self.clock.now()
        with self.lock:
            until = self._unplugged_until
            if until is not None:
                if self._listener is not None and now < until:
                    log.info("%s %d: unplugged", self.name, self.port)
                    self._drop_all()
                elif self._listener is None and now >= until:
                    self._unplugged_until = None
                    self._listen()
                    log.info("%s %d: plugged in again", self.name, self.port)
        if self._listener is None:
            self._stop.wait(self.period)
            return
        socks = [self._listener, *self._clients] + ([] if self.wake is None else [self.wake])
        ready, _, _ = select.select(socks, [], [], self.period)
        now = self.clock.now()
        with self.lock:
            for s in ready:
                if s is self.wake:
                    self.wake.drain()
                    continue
                if s is self._listener:
                    try:
                        c, _ = s.accept()
                    except OSError:
                        continue
                    if self.max_clients is not None and len(self._clients) >= self.max_clients:
                        self.refused += 1
                        c.close()
                        continue
                    c.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
                    self._clients[c] = self.session_factory()
                    self.connects += 1
                    continue
                if s not in self._clients:
                    continue
                try:
                    data = s.recv(65536)
                except OSError:
                    data = b""
                if not data:
                    self._close(s)
                    continue
                if not self.silent:
                    self._clients[s].receive(data, now)
            for c, session in list(self._clients.items()):
                session.advance(now)
                out = session.take_output()
                if out and not self.silent:
                    try:
                        c.sendall(out)
                    except OSError:
                        self._close(c)
