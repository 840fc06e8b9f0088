"""Framed JSON over TCP: a request/reply link with pushes, for links between
the processes of a game that carry Python values rather than refbox
messages (the remote backend, the simulator's station link).

Wire: each frame is a 4-byte big-endian length and a UTF-8 JSON object.
A request carries an ``id`` the reply repeats; frames without an ``id`` are
pushed by the server.

:class:`FramedServer` serves requests from its owner's loop
(:meth:`FramedServer.poll`) and may push frames of its own to its clients,
never blocking on a slow reader (what a client does not take yet waits in
that client's buffer); :class:`FramedClient` calls and waits for the reply
of its request's ``id``, keeping pushed frames in order for
:meth:`FramedClient.pushed`.  Both are built on the socket code of
:mod:`.sockets`, which the team-server link (:mod:`.tcp`) uses too.
"""
from __future__ import annotations

import json
import socket
from collections import deque

from .sockets import Connection, LengthPrefixed, Listener, wait

MAX_MESSAGE = 16 << 20           # the largest frame accepted, bytes
MAX_BUFFERED = 64 << 20          # bytes waiting for a client that reads nothing: then it is dropped


def frame(obj) -> bytes:
    """``obj`` as one frame: 4-byte big-endian length, UTF-8 JSON."""
    return LengthPrefixed.frame(json.dumps(obj, separators=(",", ":"), allow_nan=True).encode("utf-8"))


def _connection(sock: socket.socket, peer) -> Connection:
    return Connection(sock, peer, LengthPrefixed(MAX_MESSAGE), MAX_BUFFERED)


class LinkClosed(ConnectionError):
    """The other end closed the link (its process ended) or it broke."""


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
    sends a request with a fresh ``id`` and waits for the reply with that
    ``id`` (:class:`TimeoutError` when nothing arrives for ``timeout``
    seconds); frames without an ``id`` that arrive meanwhile (pushed by the
    server) are kept in order for :meth:`pushed`.  A closed link raises
    :class:`LinkClosed`; connecting may raise any :class:`OSError`."""

    def __init__(self, host: str, port: int, timeout: float = 5.0):
        self.timeout = timeout
        self._conn = _connection(socket.create_connection((host, port), timeout=timeout), (host, port))
        self._frames: deque[dict] = deque()
        self._pushed: list[dict] = []
        self._ids = 0
        self.closed = False
        self._why = ""

    def call(self, request: dict) -> dict:
        self._ids += 1
        rid = self._ids
        self._check()
        if not self._conn.queue(frame({**request, "id": rid})):
            raise self._lost("the link broke: the request could not be sent")
        while True:
            while not self._frames:
                self._check()
                self._read(block=True)
            msg = self._frames.popleft()
            if "id" not in msg:
                self._pushed.append(msg)
            elif msg["id"] == rid:
                return msg

    def pushed(self) -> list[dict]:
        """What the server pushed, in order, taking whatever has arrived (never waits)."""
        if not self._frames:
            self._check()
            self._read(block=False)
        while self._frames:
            msg = self._frames.popleft()
            if "id" not in msg:
                self._pushed.append(msg)
        out, self._pushed = self._pushed, []
        return out

    def _read(self, block: bool) -> None:
        """Take what arrived (with ``block``: wait for something, sending what waits meanwhile)."""
        conn = self._conn
        if block:
            readable, writable = wait([conn.sock], [conn.sock] if conn.tx else [], self.timeout)
            if not readable and not writable:
                raise TimeoutError(f"nothing arrived for {self.timeout:g} s")
            if writable and not conn.flush():
                raise self._lost("the link broke while sending")
            if not readable:
                return
        frames, up = conn.read()
        self._frames.extend(json.loads(body) for body in frames)
        if not up:
            why = f"the link broke: {conn.broken}" if conn.broken else "the other end closed the link"
            self._lost(why)          # what arrived before is still delivered

    def _lost(self, why: str) -> LinkClosed:
        self._why = why
        self.close()
        return LinkClosed(why)

    def _check(self) -> None:
        if self.closed:
            raise LinkClosed(self._why or "the link is closed")

    def close(self) -> None:
        if not self.closed:
            self.closed = True
            self._conn.close()


class FramedServer:
    """The serving end of framed links on ``host:port`` (0: ephemeral, see
    :attr:`port`), driven by its owner's loop: :meth:`poll` accepts,
    answers every whole request that arrived (:meth:`answer`, in order per
    client) and sends what waits.  Nothing here blocks on a client: what a
    slow client has not taken waits in its buffer (a client that lets more
    than :data:`MAX_BUFFERED` bytes pile up is dropped).  A client is a
    :class:`~.sockets.Connection` (``conn``)."""

    def __init__(self, host: str = "127.0.0.1", port: int = 0):
        self._listener = Listener(host, port)
        self.port = self._listener.port
        self._conns: dict[socket.socket, Connection] = {}

    # -- what a subclass provides ----------------------------------------------------------------
    def answer(self, conn: Connection, body: bytes) -> dict | None:
        """The reply to one request (None: no reply)."""
        raise NotImplementedError

    def connected(self, conn: Connection) -> None:
        """A client connected."""

    # -- serving ----------------------------------------------------------------------------------
    @property
    def clients(self) -> list[Connection]:
        return list(self._conns.values())

    @property
    def unsent(self) -> int:
        """Bytes waiting for clients that have not taken them yet."""
        return sum(len(conn.tx) for conn in self._conns.values())

    def poll(self, timeout: float) -> int:
        """Serve whatever arrives within ``timeout`` seconds; returns the requests answered."""
        conns = self._conns
        readable, writable = wait([self._listener.sock, *conns], [s for s, c in conns.items() if c.tx], timeout)
        served = 0
        for sock in writable:
            conn = conns.get(sock)
            if conn is not None and not conn.flush():
                self._drop(conn)
        for sock in readable:
            if sock is self._listener.sock:
                for new, addr in self._listener.accept():
                    conn = conns[new] = _connection(new, addr)
                    self.connected(conn)
            elif sock in conns:
                served += self._read(conns[sock])
        return served

    def send(self, conn: Connection, obj) -> None:
        """Queue ``obj`` for ``conn`` and send what the socket takes now."""
        if conn.sock not in self._conns:
            return
        if not conn.queue(frame(obj)):
            self._drop(conn)

    def push(self, obj) -> int:
        """Send ``obj`` to every client; returns how many."""
        clients = self.clients
        for conn in clients:
            self.send(conn, obj)
        return len(clients)

    def _read(self, conn: Connection) -> int:
        frames, up = conn.read()
        served = 0
        for body in frames:
            if conn.sock not in self._conns:
                break
            reply = self.answer(conn, body)
            served += 1
            if reply is not None:
                self.send(conn, reply)
        if not up:
            self._drop(conn)
        return served

    def _drop(self, conn: Connection) -> None:
        if self._conns.pop(conn.sock, None) is not None:
            conn.close()

    def close(self) -> None:
        for conn in list(self._conns.values()):
            self._drop(conn)
        self._listener.close()
