"""Framed TCP streams: a reconnecting client and a multi-client server.

Frames are the same v2 frames as on UDP (8-byte header, then payload_size
bytes), so a stream is cut by reading 8 bytes and then payload_size bytes.
With a key (the team-server link) the link is secured with authenticated
encryption and sequence numbers (:mod:`.secure`): a peer without the key
can neither read nor task (the server drops its frames and, by default,
disconnects it), and recorded or altered frames are dropped and counted.
``cipher="aes-128-cbc"`` instead encrypts every frame as the refbox's team
channel does (for league peers).  Sockets are non-blocking; outgoing bytes are
buffered and flushed as the socket accepts them (:mod:`.sockets`, the
socket code shared with :mod:`.jsonlink`).
"""
from __future__ import annotations

import errno
import logging
import os
import select
import socket
import time
from collections.abc import Callable
from typing import Any

from ..clock import Clock
from . import stats as S
from .codec import FrameCodec
from .crypto import TEAM_CIPHER
from .framing import FRAME_V2, MAX_STREAM_PAYLOAD, StreamReassembler
from .ports import TEAM_SERVER_PORT
from .registry import MessageRegistry
from .secure import CLIENT, LINK_CIPHER, SERVER, SecureEnd, stream_crypto
from .sockets import MAX_TX_BUFFER, Connection, Listener, wait
from .transport import CONNECTED, DISCONNECTED, PumpedTransport, Received

log = logging.getLogger("rll_bt.comm")

#: the cipher id a message opened by a secured link reports in :attr:`Received.cipher`
SEALED_CIPHER = 0x81


def _decode_frames(owner, conn: Connection, frames: list[bytes], source: Any) -> str | None:
    """Decode and deliver ``frames``; the first crypto-related drop cause, if any."""
    crypto_cause = None
    for frame in frames:
        if owner.secure is not None:
            message, replies, cause = owner.secure.open(conn, frame)
            for reply in replies:
                conn.queue(reply)
            decoded = None
            if message is not None:
                decoded, cause = owner.codec.decode_message(message, SEALED_CIPHER)
        else:
            decoded, cause = owner.codec.try_decode(frame)
        if decoded is not None:
            owner._deliver(Received.of(decoded, owner.channel, source, owner.clock.now()))
        elif cause in S.CRYPTO_CAUSES and crypto_cause is None:
            crypto_cause = cause
    if conn.broken:
        owner.stats.add(conn.broken.cause, conn.broken.detail)
    return crypto_cause


class _Framed:
    """What both ends share: their connections cut refbox frames, and on a
    secured link each connection starts with a hello."""

    _frame_version: int
    _max_payload: int
    secure: SecureEnd | None

    def _connection(self, sock: socket.socket, peer: Any) -> Connection:
        conn = Connection(sock, peer, StreamReassembler(self._frame_version, self._max_payload), MAX_TX_BUFFER)
        if self.secure is not None:
            conn.queue(self.secure.connect(conn))
        return conn

    def _frame(self, conn: Connection, msg) -> bytes | None:
        """The frame to queue for ``msg`` on ``conn`` (None: it waits for the peer's hello)."""
        if self.secure is None:
            return self.codec.encode(msg)
        return self.secure.seal(conn, self.codec.message_bytes(msg))

    def _forget(self, conn: Connection) -> None:
        if self.secure is not None:
            self.secure.forget(conn)


class StreamClient(_Framed, PumpedTransport):
    """Connects to ``host:port`` and keeps reconnecting with exponential backoff.

    ``backoff_initial``/``backoff_max``: seconds of ``clock`` between attempts
    (doubling after each failure, reset once connected).  ``connect_timeout``:
    seconds an attempt may take.  ``send`` returns False while disconnected
    (the message is not queued).  :attr:`Received.source` is ``(host, port)``.
    """

    def __init__(self, host: str, port: int = TEAM_SERVER_PORT, *, registry: MessageRegistry,
                 key: str | bytes | None = None, cipher: int | str = LINK_CIPHER,
                 clock: Clock | None = None, channel: str = "stream",
                 backoff_initial: float = 0.1, backoff_max: float = 5.0,
                 connect_timeout: float = 2.0, frame_version: int = FRAME_V2,
                 max_payload: int = MAX_STREAM_PAYLOAD,
                 iv_source: Callable[[int], bytes] = os.urandom):
        super().__init__(channel, clock)
        self.host, self.port = host, int(port)
        self.stats = S.DropStats(f"{channel} tcp client {host}:{port}")
        codec_key, self.secure = stream_crypto(key, cipher, CLIENT, self.stats)
        self.codec = FrameCodec(registry, key=codec_key, cipher=TEAM_CIPHER if codec_key is None else cipher,
                                frame_version=frame_version, stats=self.stats, iv_source=iv_source)
        self.backoff_initial, self.backoff_max = backoff_initial, backoff_max
        self.connect_timeout = connect_timeout
        self._frame_version, self._max_payload = frame_version, max_payload
        self._conn: Connection | None = None
        self._connecting: tuple[socket.socket, float] | None = None
        self._backoff = backoff_initial
        self._next_attempt = self.clock.now()
        self._warned_connect = False
        self.connections = 0   #: successful connects so far
        with self._io_lock:
            self._progress()

    @property
    def address(self) -> tuple[str, int]:
        return (self.host, self.port)

    @property
    def connected(self) -> bool:
        return self._conn is not None

    @property
    def retry_at(self) -> float | None:
        """Clock time of the next connection attempt; None while connected or connecting."""
        if self._conn is not None or self._connecting is not None:
            return None
        return self._next_attempt

    # -- connection state machine ----------------------------------------------
    def _progress(self) -> None:
        if self._conn is not None or self._closed:
            return
        now = self.clock.now()
        if self._connecting is None:
            if now < self._next_attempt:
                return
            s = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
            s.setblocking(False)
            try:
                err = s.connect_ex(self.address)
            except OSError as exc:
                err = exc.errno or errno.EHOSTUNREACH
            if err == 0:
                self._established(s)
            elif err in (errno.EINPROGRESS, errno.EWOULDBLOCK, errno.EALREADY):
                self._connecting = (s, now)
            else:
                s.close()
                self._failed(err)
            return
        s, started = self._connecting
        try:
            _, writable, _ = select.select([], [s], [], 0)
        except (OSError, ValueError):
            writable = [s]            # let SO_ERROR tell
        if writable:
            err = s.getsockopt(socket.SOL_SOCKET, socket.SO_ERROR)
            self._connecting = None
            if err == 0:
                self._established(s)
            else:
                s.close()
                self._failed(err)
        elif now - started > self.connect_timeout:
            self._connecting = None
            s.close()
            self._failed(errno.ETIMEDOUT)

    def _established(self, s: socket.socket) -> None:
        self._conn = self._connection(s, self.address)
        self._backoff = self.backoff_initial
        self._warned_connect = False
        self.connections += 1
        log.info("%s: connected to %s:%d", self.channel, self.host, self.port)
        self._event(CONNECTED, self.address)

    def _failed(self, err: int) -> None:
        if not self._warned_connect:
            self._warned_connect = True
            log.warning("%s: cannot connect to %s:%d (%s); retrying with backoff up to %.1f s",
                        self.channel, self.host, self.port, os.strerror(err), self.backoff_max)
        self._schedule_retry()

    def _schedule_retry(self) -> None:
        self._next_attempt = self.clock.now() + self._backoff
        self._backoff = min(self._backoff * 2, self.backoff_max)

    def _lost(self) -> None:
        if self._conn is None:
            return
        self._forget(self._conn)
        self._conn.close()
        self._conn = None
        log.info("%s: connection to %s:%d lost", self.channel, self.host, self.port)
        self._event(DISCONNECTED, self.address)
        self._schedule_retry()

    def reconnect(self) -> None:
        """Drop the connection (a peer that went silent) and connect again at once."""
        with self._io_lock:
            self._lost()
            self._backoff = self.backoff_initial
            self._next_attempt = self.clock.now()

    # -- transport interface ---------------------------------------------------
    def send(self, msg) -> bool:
        if self.secure is None:
            self.codec.encode(msg)             # the caller's mistakes raise here, connected or not
        else:
            self.codec.message_bytes(msg)
        with self._io_lock:
            if self._closed:
                return False
            self._progress()
            if self._conn is None:
                return False
            frame = self._frame(self._conn, msg)
            if frame is not None and not self._conn.queue(frame):
                self._lost()
                return False
            return True

    def _pump(self) -> None:
        self._progress()
        conn = self._conn
        if conn is None:
            return
        alive = conn.flush()
        frames, up = conn.read()
        _decode_frames(self, conn, frames, self.address)
        if not (alive and up):
            self._lost()

    def _wait_io(self, timeout: float) -> None:
        timeout = max(0.0, timeout)
        rd, wr = [], []
        if self._conn is not None:
            rd.append(self._conn.sock)
            if self._conn.tx:
                wr.append(self._conn.sock)
        elif self._connecting is not None:
            wr.append(self._connecting[0])
        else:
            timeout = min(timeout, max(0.0, self._next_attempt - self.clock.now()))
        wait(rd, wr, timeout)

    def wait_connected(self, timeout: float) -> bool:
        """Block up to ``timeout`` wall seconds until connected; True if connected."""
        deadline = time.monotonic() + timeout
        while not self.connected and not self._closed:
            left = deadline - time.monotonic()
            if left <= 0:
                break
            if self._thread is None:
                self._wait_io(min(left, 0.05))
                self._pump_locked()
            else:
                time.sleep(min(left, 0.01))
        return self.connected

    def _close_io(self) -> None:
        if self._conn is not None:
            self._conn.flush()
            self._conn.close()
            self._conn = None
        if self._connecting is not None:
            self._connecting[0].close()
            self._connecting = None


class StreamServer(_Framed, PumpedTransport):
    """Accepts framed TCP clients on ``host:port`` (0 = an ephemeral port, see :attr:`port`).

    Each client gets an int id (:attr:`Received.source`, :class:`LinkEvent`
    ``peer``).  With ``key`` the link is encrypted; with
    ``drop_unauthenticated`` a client whose frame fails crypto (plain on an
    encrypted link, wrong key) is disconnected.
    """

    def __init__(self, port: int = TEAM_SERVER_PORT, *, registry: MessageRegistry,
                 host: str = "0.0.0.0", key: str | bytes | None = None,
                 cipher: int | str = LINK_CIPHER, clock: Clock | None = None,
                 channel: str = "stream", drop_unauthenticated: bool = True,
                 frame_version: int = FRAME_V2, max_payload: int = MAX_STREAM_PAYLOAD,
                 iv_source: Callable[[int], bytes] = os.urandom, backlog: int = 16):
        super().__init__(channel, clock)
        self.stats = S.DropStats(f"{channel} tcp server :{port}")
        codec_key, self.secure = stream_crypto(key, cipher, SERVER, self.stats)
        self.codec = FrameCodec(registry, key=codec_key, cipher=TEAM_CIPHER if codec_key is None else cipher,
                                frame_version=frame_version, stats=self.stats, iv_source=iv_source)
        self.drop_unauthenticated = drop_unauthenticated
        self._frame_version, self._max_payload = frame_version, max_payload
        self._listener = Listener(host, int(port), backlog)
        self.host = host
        self.port = self._listener.port
        self.stats.name = f"{channel} tcp server :{self.port}"
        self._conns: dict[int, Connection] = {}
        self._next_id = 1

    def clients(self) -> list[int]:
        """Ids of the connected clients, oldest first."""
        return list(self._conns)

    def peer_address(self, client: int) -> tuple[str, int] | None:
        conn = self._conns.get(client)
        return conn.peer if conn else None

    def send(self, msg, to: int | None = None) -> bool:
        """Send to client ``to``, or to every client when None.  True if at least one got it."""
        sent = False
        with self._io_lock:
            targets = list(self._conns) if to is None else [to]
            for cid in targets:
                conn = self._conns.get(cid)
                if conn is None:
                    continue
                frame = self._frame(conn, msg)
                if frame is None or conn.queue(frame):
                    sent = True
                else:
                    self._drop(cid)
        return sent

    def disconnect(self, client: int) -> None:
        with self._io_lock:
            self._drop(client)

    def _drop(self, cid: int) -> None:
        conn = self._conns.pop(cid, None)
        if conn is not None:
            self._forget(conn)
            conn.close()
            self._event(DISCONNECTED, cid)

    def _pump(self) -> None:
        for s, addr in self._listener.accept():
            cid, self._next_id = self._next_id, self._next_id + 1
            self._conns[cid] = self._connection(s, addr)
            self._event(CONNECTED, cid)
        for cid, conn in list(self._conns.items()):
            alive = conn.flush()
            frames, up = conn.read()
            bad = _decode_frames(self, conn, frames, cid)
            if bad and self.drop_unauthenticated:
                log.info("%s: disconnecting client %d %s (%s)", self.channel, cid, conn.peer, bad)
                up = False
            if not (alive and up):
                self._drop(cid)

    def _wait_io(self, timeout: float) -> None:
        rd = [self._listener.sock] + [c.sock for c in self._conns.values()]
        wr = [c.sock for c in self._conns.values() if c.tx]
        wait(rd, wr, timeout)

    def _close_io(self) -> None:
        for cid in list(self._conns):
            conn = self._conns.pop(cid)
            conn.flush()
            conn.close()
        self._listener.close()
