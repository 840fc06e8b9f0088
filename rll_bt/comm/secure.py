"""Authenticated encryption for the team-server link (team server <-> agents).

The refbox's team channels use protobuf_comm's AES-CBC, which hides a frame
but does not authenticate it: a captured frame can be replayed and altered
ciphertext is not detected.  The link between our team server and its robots
is ours alone, so it uses AES-256-GCM with sequence numbers instead, in the
same v2 frame header (with cipher ids protobuf_comm does not use):

- On connecting, each end sends a *hello* frame (cipher id :data:`HELLO`):
  its role and 16 fresh random bytes.  Both ends derive the session keys from
  the team key and both nonces (HKDF-SHA256, salt = server nonce + client
  nonce), one key per direction.  A session's keys are new on every
  connection, so frames recorded from an earlier session never decrypt.
- Every message then travels *sealed* (cipher id :data:`SEALED`)::

      [frame header 8: 2, SEALED, 0, payload_size][seq u64][AES-GCM(message header + protobuf)]

  The nonce is the sequence number, the associated data the frame header and
  the sequence number, so header, sequence and body are all authenticated.
  A receiver accepts only sequence numbers above the last one it accepted:
  a replayed frame is dropped (``replay``), a forged or altered one fails its
  tag (``auth_failure``); both are counted, neither reaches the application.

A peer without the key can send hellos but no frame that opens.  The
handshake carries no key material; the first sealed frame confirms the key.
This module is sans-IO: :class:`SecureSession` turns bytes into bytes and
the stream transports (TCP and the in-process bus) carry them.
"""
from __future__ import annotations

import hashlib
import hmac
import os
import struct
from collections.abc import Callable

from cryptography.exceptions import InvalidTag
from cryptography.hazmat.primitives.ciphers.aead import AESGCM

from . import stats as S
from .framing import FRAME_HEADER_SIZE, FRAME_V2, Drop, FrameHeader

#: frame-header cipher ids of this link (protobuf_comm uses 0..4)
HELLO, SEALED = 0x80, 0x81
#: the ``cipher`` a stream transport takes for this link (its default when given a key)
LINK_CIPHER = "aes-256-gcm-link"
SERVER, CLIENT = 0x53, 0x43          # "S", "C"
NONCE_SIZE = 16
_SEQ = struct.Struct(">Q")
_TAG = 16
_INFO = b"rll-bt team link v1"


def _hkdf(ikm: bytes, salt: bytes, info: bytes, length: int) -> bytes:
    """HKDF-SHA256 (RFC 5869)."""
    prk = hmac.new(salt, ikm, hashlib.sha256).digest()
    out, block, i = b"", b"", 1
    while len(out) < length:
        block = hmac.new(prk, block + info + bytes([i]), hashlib.sha256).digest()
        out += block
        i += 1
    return out[:length]


def psk_from_key(key: str | bytes) -> bytes:
    """The 32-byte pre-shared secret of a team key string."""
    if key is None or len(key) == 0:
        raise ValueError("an empty key is not allowed on the team-server link")
    raw = key.encode("utf-8") if isinstance(key, str) else bytes(key)
    return hashlib.sha256(b"rll-bt link key\0" + raw).digest()


class SecureSession:
    """One end of one connection of the secured link.

    ``role`` is :data:`SERVER` or :data:`CLIENT`.  Send :meth:`hello` when the
    connection opens, feed every frame that arrives to :meth:`open` (which
    returns the message bytes, or None for a hello it consumed, and raises
    :class:`~rll_bt.comm.framing.Drop` for a frame to drop), and
    :meth:`seal` message bytes to send once :attr:`ready`.
    """

    def __init__(self, key: str | bytes, role: int, *, random: Callable[[int], bytes] = os.urandom):
        if role not in (SERVER, CLIENT):
            raise ValueError("role must be SERVER or CLIENT")
        self.role = role
        self._psk = psk_from_key(key)
        self._random = random
        self.nonce = random(NONCE_SIZE)
        self._send: AESGCM | None = None
        self._recv: AESGCM | None = None
        self._send_seq = 0
        self._recv_seq = -1
        self.peer_nonce: bytes | None = None

    @property
    def ready(self) -> bool:
        """True once the peer's hello arrived (frames can be sealed and opened)."""
        return self._send is not None

    def hello(self) -> bytes:
        """The hello frame to send first on a new connection."""
        body = bytes([self.role]) + self.nonce
        return FrameHeader(HELLO, len(body)).pack() + body

    def _accept_hello(self, body: bytes) -> None:
        if len(body) != 1 + NONCE_SIZE or body[0] == self.role or body[0] not in (SERVER, CLIENT):
            raise Drop(S.HANDSHAKE, f"bad hello ({len(body)} bytes)")
        if self.ready:
            raise Drop(S.HANDSHAKE, "a second hello on one connection")
        self.peer_nonce = bytes(body[1:])
        server, client = ((self.nonce, self.peer_nonce) if self.role == SERVER
                          else (self.peer_nonce, self.nonce))
        keys = _hkdf(self._psk, server + client, _INFO, 64)
        to_client, to_server = AESGCM(keys[:32]), AESGCM(keys[32:])
        self._send, self._recv = ((to_client, to_server) if self.role == SERVER
                                  else (to_server, to_client))

    def seal(self, message: bytes) -> bytes:
        """The sealed frame carrying ``message`` (message header + protobuf)."""
        if self._send is None:
            raise RuntimeError("seal() before the peer's hello: queue the message until ready")
        seq = _SEQ.pack(self._send_seq)
        self._send_seq += 1
        header = FrameHeader(SEALED, len(seq) + len(message) + _TAG).pack()
        return header + seq + self._send.encrypt(b"\0\0\0\0" + seq, message, header + seq)

    def open(self, frame: bytes) -> bytes | None:
        """The message bytes in ``frame``; None for a hello (consumed).  Raises
        :class:`~rll_bt.comm.framing.Drop` with cause ``handshake``,
        ``auth_failure``, ``replay``, ``plain_on_encrypted`` or a framing cause."""
        hdr = FrameHeader.unpack(frame)
        if len(frame) != FRAME_HEADER_SIZE + hdr.payload_size:
            raise Drop(S.SIZE_MISMATCH, f"frame of {len(frame)} bytes, header says 8 + {hdr.payload_size}")
        body = frame[FRAME_HEADER_SIZE:]
        if hdr.cipher == HELLO:
            self._accept_hello(body)
            return None
        if hdr.cipher != SEALED:
            raise Drop(S.PLAIN_ON_ENCRYPTED if hdr.cipher == 0 else S.BAD_CIPHER,
                       f"cipher {hdr.cipher} frame on the secured link")
        if self._recv is None:
            raise Drop(S.HANDSHAKE, "sealed frame before the hello")
        if len(body) < _SEQ.size + _TAG:
            raise Drop(S.TOO_SHORT, f"sealed payload of {len(body)} bytes")
        seq_bytes = bytes(body[:_SEQ.size])
        try:
            message = self._recv.decrypt(b"\0\0\0\0" + seq_bytes, bytes(body[_SEQ.size:]),
                                         bytes(frame[:FRAME_HEADER_SIZE]) + seq_bytes)
        except InvalidTag:
            raise Drop(S.AUTH_FAILURE, "tag check failed (altered frame or wrong key)") from None
        seq = _SEQ.unpack(seq_bytes)[0]
        if seq <= self._recv_seq:
            raise Drop(S.REPLAY, f"sequence {seq} after {self._recv_seq}")
        self._recv_seq = seq
        return message


class SecureEnd:
    """The sessions of one stream end: a server's clients or a client's connection.

    ``conn`` is whatever names a connection (a client id, a socket object).
    :meth:`connect` gives the hello to send on a new connection; :meth:`seal`
    gives the frame for a message, or None while the peer's hello is awaited
    (the message waits and :meth:`open` returns it sealed once the hello
    comes); :meth:`open` gives ``(message bytes or None, frames to send now,
    drop cause or None)`` and counts drops in ``stats``.
    """

    def __init__(self, key: str | bytes, role: int, stats: S.DropStats, *, max_waiting: int = 256):
        psk_from_key(key)                          # refuse an empty key at once
        self.key, self.role, self.stats = key, role, stats
        self.max_waiting = max_waiting
        self._sessions: dict[object, SecureSession] = {}
        self._waiting: dict[object, list[bytes]] = {}

    def connect(self, conn) -> bytes:
        session = self._sessions[conn] = SecureSession(self.key, self.role)
        self._waiting[conn] = []
        return session.hello()

    def forget(self, conn) -> None:
        self._sessions.pop(conn, None)
        self._waiting.pop(conn, None)

    def seal(self, conn, message: bytes) -> bytes | None:
        session = self._sessions.get(conn)
        if session is None:
            raise KeyError(f"no secured connection {conn!r}")
        if session.ready:
            return session.seal(message)
        waiting = self._waiting[conn]
        if len(waiting) >= self.max_waiting:     # a peer that never says hello holds no memory
            waiting.pop(0)
            self.stats.add(S.HANDSHAKE, "no hello from the peer: oldest waiting message dropped")
        waiting.append(message)
        return None

    def open(self, conn, frame: bytes) -> tuple[bytes | None, list[bytes], str | None]:
        session = self._sessions.get(conn)
        if session is None:
            return None, [], None
        try:
            message = session.open(frame)
        except Drop as drop:
            self.stats.add(drop.cause, drop.detail)
            return None, [], drop.cause
        if message is None:                         # the hello: what waited goes out now
            waiting, self._waiting[conn] = self._waiting[conn], []
            return None, [session.seal(m) for m in waiting], None
        return message, [], None


def stream_crypto(key, cipher, role: int, stats: S.DropStats) -> tuple[str | bytes | None, SecureEnd | None]:
    """For a stream transport: ``(key for its FrameCodec, SecureEnd or None)``.
    With a key and :data:`LINK_CIPHER` the link is secured and the codec plain;
    with a protobuf_comm cipher (e.g. "aes-128-cbc", for a league peer) the
    codec encrypts as the refbox does."""
    if key is not None and cipher == LINK_CIPHER:
        return None, SecureEnd(key, role, stats)
    return key, None


def is_secure_frame(frame: bytes) -> bool:
    """Whether a frame belongs to the secured link (hello or sealed)."""
    return len(frame) >= 2 and frame[0] == FRAME_V2 and frame[1] in (HELLO, SEALED)
