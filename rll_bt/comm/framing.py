"""protobuf_comm frame and message headers (refbox-protocol §1).

All integers big-endian.  A v2 frame is::

    [frame header 8: version=2 u8, cipher u8, reserved u16 = 0, payload_size u32]
    plain:     [message header 4: comp_id u16, msg_type u16][protobuf]
               payload_size = 4 + len(protobuf); the frame is exactly 8 + payload_size bytes
    encrypted: [IV 16 (CBC only)][AES(PKCS7(message header + protobuf))]
               payload_size = len(IV) + len(ciphertext); receivers ignore it and
               decrypt everything after the 8-byte header

A v1 frame (refboxes before RC2014, decode only) is
``[comp_id u16, msg_type u16, payload_size u32][protobuf]`` with
``payload_size = len(protobuf)`` and no encryption.
"""
from __future__ import annotations

import struct
from dataclasses import dataclass

from . import stats as S

FRAME_HEADER_SIZE = 8
MESSAGE_HEADER_SIZE = 4
FRAME_V1, FRAME_V2 = 1, 2
#: protobuf_comm's max_packet_length: the UDP receive buffer, in bytes
MAX_DATAGRAM = 1024
#: largest stream (TCP / bus stream) payload accepted, in bytes
MAX_STREAM_PAYLOAD = 1 << 20

_V2 = struct.Struct(">BBHI")
_V1 = struct.Struct(">HHI")
_MSG = struct.Struct(">HH")


class Drop(Exception):
    """Internal: a frame is dropped for ``cause`` (one of :data:`rll_bt.comm.stats.CAUSES`)."""

    def __init__(self, cause: str, detail: str = ""):
        super().__init__(cause, detail)
        self.cause, self.detail = cause, detail


@dataclass(frozen=True)
class FrameHeader:
    """Frame header v2: ``version`` (2), ``cipher`` id, ``payload_size`` in bytes."""

    cipher: int
    payload_size: int
    version: int = FRAME_V2

    def pack(self) -> bytes:
        return _V2.pack(self.version, self.cipher, 0, self.payload_size)

    @classmethod
    def unpack(cls, data: bytes) -> FrameHeader:
        """Header from the first 8 bytes; :class:`Drop` if short or not version 2."""
        if len(data) < FRAME_HEADER_SIZE:
            raise Drop(S.TOO_SHORT, f"{len(data)} bytes, a frame header needs 8")
        version, cipher, _reserved, size = _V2.unpack_from(data)
        if version != FRAME_V2:
            raise Drop(S.BAD_VERSION, f"header version {version}, expected 2")
        return cls(cipher, size, version)


@dataclass(frozen=True)
class FrameHeaderV1:
    """Legacy frame header v1 (decode only): ``payload_size`` = protobuf length."""

    comp_id: int
    msg_type: int
    payload_size: int

    @classmethod
    def unpack(cls, data: bytes) -> FrameHeaderV1:
        if len(data) < FRAME_HEADER_SIZE:
            raise Drop(S.TOO_SHORT, f"{len(data)} bytes, a v1 frame header needs 8")
        return cls(*_V1.unpack_from(data))


@dataclass(frozen=True)
class MessageHeader:
    """The 4-byte message header: ``comp_id``, ``msg_type``."""

    comp_id: int
    msg_type: int

    def pack(self) -> bytes:
        return _MSG.pack(self.comp_id, self.msg_type)

    @classmethod
    def unpack(cls, data: bytes) -> MessageHeader:
        if len(data) < MESSAGE_HEADER_SIZE:
            raise Drop(S.TOO_SHORT, f"{len(data)} bytes of payload, a message header needs 4")
        return cls(*_MSG.unpack_from(data))


def plain_frame(comp_id: int, msg_type: int, body: bytes) -> bytes:
    """A complete unencrypted v2 frame carrying protobuf bytes ``body``."""
    payload = MessageHeader(comp_id, msg_type).pack() + body
    return FrameHeader(0, len(payload)).pack() + payload


def encrypted_frame(cipher: int, iv_and_ciphertext: bytes) -> bytes:
    """A complete encrypted v2 frame; payload_size = len(IV) + len(ciphertext) as peer.cpp sets it."""
    return FrameHeader(cipher, len(iv_and_ciphertext)).pack() + iv_and_ciphertext


class StreamReassembler:
    """Cuts a byte stream (TCP) into whole frames: 8-byte header, then payload_size bytes.

    :meth:`feed` returns the complete frames (header included) found so far.
    A header that cannot be trusted (wrong version, payload over
    ``max_payload``) makes the stream unusable: :attr:`broken` is set to the
    :class:`Drop` and the owner should close the connection.
    """

    def __init__(self, frame_version: int = FRAME_V2, max_payload: int = MAX_STREAM_PAYLOAD):
        if frame_version not in (FRAME_V1, FRAME_V2):
            raise ValueError(f"frame version must be 1 or 2, not {frame_version}")
        self.frame_version = frame_version
        self.max_payload = max_payload
        self._buf = bytearray()
        self.broken: Drop | None = None

    def feed(self, data: bytes) -> list[bytes]:
        if self.broken:
            return []
        self._buf += data
        frames = []
        while len(self._buf) >= FRAME_HEADER_SIZE:
            try:
                if self.frame_version == FRAME_V2:
                    size = FrameHeader.unpack(self._buf).payload_size
                else:
                    size = FrameHeaderV1.unpack(self._buf).payload_size
            except Drop as drop:
                self.broken = drop
                break
            if size > self.max_payload:
                self.broken = Drop(S.OVERSIZE, f"stream payload_size {size} > {self.max_payload}")
                break
            end = FRAME_HEADER_SIZE + size
            if len(self._buf) < end:
                break
            frames.append(bytes(self._buf[:end]))
            del self._buf[:end]
        if self.broken:
            self._buf.clear()
        return frames

    @property
    def pending(self) -> int:
        """Bytes buffered towards an incomplete frame."""
        return len(self._buf)
