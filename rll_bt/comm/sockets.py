"""Non-blocking TCP connections cut into frames: the socket code every
stream link shares.

- :class:`Connection`: one connected socket, non-blocking; what arrives is
  cut into whole frames by a *cutter* (an object with ``feed(bytes) ->
  [frame]`` and ``broken``, None until the stream cannot be trusted:
  :class:`~.framing.StreamReassembler` for refbox frames,
  :class:`LengthPrefixed` for framed JSON); what is sent waits in a buffer
  until the socket takes it, up to ``max_tx`` bytes.
- :class:`Listener`: a listening socket handing out accepted sockets.
- :func:`wait`: block until sockets are readable or writable, or a timeout.

Used by :mod:`.tcp` (the refbox-framed team-server link) and
:mod:`.jsonlink` (framed JSON between the processes of a game).
"""
from __future__ import annotations

import select
import socket
import struct
from typing import Any

#: a peer whose unsent bytes would exceed this is considered dead, bytes
MAX_TX_BUFFER = 8 << 20
RECV_CHUNK = 65536


class Broken(ValueError):
    """Why a byte stream cannot be cut into frames any more (``cause``: a
    :mod:`.stats` cause where one applies, ``detail``: a sentence)."""

    def __init__(self, cause: str, detail: str):
        super().__init__(detail)
        self.cause, self.detail = cause, detail


class LengthPrefixed:
    """Cuts a stream of frames that are a 4-byte big-endian length and that
    many bytes; :meth:`feed` returns the bodies.  A length over ``max_size``
    breaks the stream (:attr:`broken`)."""

    HEADER = struct.Struct(">I")

    def __init__(self, max_size: int):
        self.max_size = max_size
        self._buf = bytearray()
        self.broken: Broken | None = None

    @classmethod
    def frame(cls, body: bytes) -> bytes:
        return cls.HEADER.pack(len(body)) + body

    def feed(self, data: bytes) -> list[bytes]:
        if self.broken:
            return []
        buf, n = self._buf, self.HEADER.size
        buf += data
        out = []
        while len(buf) >= n:
            (size,) = self.HEADER.unpack_from(buf)
            if size > self.max_size:
                self.broken = Broken("oversize", f"a frame of {size} bytes (at most {self.max_size})")
                buf.clear()
                break
            if len(buf) < n + size:
                break
            out.append(bytes(buf[n:n + size]))
            del buf[:n + size]
        return out


class Connection:
    """One framed, non-blocking TCP connection to ``peer`` (see the module doc)."""

    def __init__(self, sock: socket.socket, peer: Any, cutter, max_tx: int = MAX_TX_BUFFER):
        sock.setblocking(False)
        try:
            sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        except OSError:
            pass
        self.sock, self.peer = sock, peer
        self.rx = cutter
        self.tx = bytearray()
        self.max_tx = max_tx

    @property
    def broken(self):
        """Why the incoming stream cannot be cut any more (None while it can)."""
        return self.rx.broken

    def queue(self, frame: bytes) -> bool:
        """Buffer and try to send ``frame``; False if the connection is dead
        (the socket failed, or more than ``max_tx`` bytes would wait)."""
        if len(self.tx) + len(frame) > self.max_tx:
            return False
        self.tx += frame
        return self.flush()

    def flush(self) -> bool:
        """Send what the socket takes now; False if the connection is dead."""
        while self.tx:
            try:
                n = self.sock.send(self.tx)
            except (BlockingIOError, InterruptedError):
                return True
            except OSError:
                return False
            del self.tx[:n]
        return True

    def read(self) -> tuple[list[bytes], bool]:
        """Whole frames received so far and whether the connection is still up
        (False once the peer closed, the socket failed or the stream broke)."""
        frames: list[bytes] = []
        while True:
            try:
                data = self.sock.recv(RECV_CHUNK)
            except (BlockingIOError, InterruptedError):
                return frames, True
            except OSError:
                return frames, False
            if not data:
                return frames, False
            frames += self.rx.feed(data)
            if self.rx.broken:
                return frames, False

    def close(self) -> None:
        try:
            self.sock.close()
        except OSError:
            pass


class Listener:
    """A non-blocking listening socket on ``host:port`` (0: an ephemeral
    port, see :attr:`port`)."""

    def __init__(self, host: str, port: int, backlog: int = 16):
        sock = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
        try:
            sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
            sock.bind((host, int(port)))
            sock.listen(backlog)
            sock.setblocking(False)
        except OSError:
            sock.close()
            raise
        self.sock = sock
        self.host = host
        self.port = sock.getsockname()[1]

    def accept(self) -> list[tuple[socket.socket, Any]]:
        """Every connection waiting now, as (socket, address)."""
        out = []
        while True:
            try:
                out.append(self.sock.accept())
            except (BlockingIOError, InterruptedError):
                return out
            except OSError:
                return out

    def close(self) -> None:
        self.sock.close()


def wait(readable, writable, timeout: float) -> tuple[list, list]:
    """The sockets (or objects with ``fileno``) of ``readable`` and ``writable``
    that are ready, waiting at most ``timeout`` seconds; nothing on a socket error."""
    try:
        rd, wr, _ = select.select(list(readable), list(writable), [], max(0.0, timeout))
    except (OSError, ValueError):
        return [], []
    return rd, wr
