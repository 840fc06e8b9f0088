"""Framed JSON over TCP: a request/reply link with pushes, for links between
the processes of a game that carry Python values rather than refbox
messages (the remote backend, the simulator's station link).

Wire: each frame is a 4-byte big-endian length and a UTF-8 JSON object.
A request carries an ``id`` the reply repeats; frames without an ``id`` are
pushed by the server.

:class:`FramedServer` serves requests from its owner's loop (:meth:`FramedServer.poll`)
and may push frames of its own to its clients, never blocking on a slow
reader (what a client does not take yet waits in that client's buffer);
:class:`FramedClient` calls and waits for the reply of its request's ``id``,
keeping pushed frames in order for :meth:`FramedClient.pushed`.
"""
from __future__ import annotations

import json
import selectors
import socket
import struct
from collections import deque

_LEN = struct.Struct(">I")
MAX_MESSAGE = 16 << 20
MAX_BUFFERED = 64 << 20          # bytes waiting for a client that reads nothing: then it is dropped


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


