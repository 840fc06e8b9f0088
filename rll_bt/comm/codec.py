"""Encoding messages to frames and frames back to messages, with crypto.

A :class:`FrameCodec` is what every transport uses: it holds the registry,
the optional team key and the drop counters.  ``decode`` never raises; a
frame it cannot use is counted by cause in :attr:`FrameCodec.stats`.
"""
from __future__ import annotations

import os
from collections.abc import Callable
from dataclasses import dataclass

from . import stats as S
from .crypto import CIPHERS, TEAM_CIPHER, FrameCrypto
from .errors import FrameTooLarge
from .framing import (
    FRAME_HEADER_SIZE,
    FRAME_V1,
    FRAME_V2,
    Drop,
    FrameHeader,
    FrameHeaderV1,
    MessageHeader,
    encrypted_frame,
    plain_frame,
)
from .registry import MessageRegistry, require_comp_type


@dataclass(frozen=True)
class Decoded:
    """A message taken from a frame: the message, its header pair, the frame's cipher id."""

    msg: object
    comp_id: int
    msg_type: int
    cipher: int = 0


class FrameCodec:
    """Frames messages for one channel.

    ``registry``: the message classes this receiver accepts.
    ``key``/``cipher``: team key string and cipher id (default 2, AES-128-CBC)
    to encrypt with; None sends and expects plain frames.  A codec with a key
    drops plain frames, one without drops encrypted frames.
    ``frame_version``: 2, or 1 to *decode* legacy frames (v1 cannot encode or encrypt).
    ``max_frame``: largest whole frame in bytes (1024 for UDP, None for no limit).
    ``stats``: where drops are counted (a new :class:`DropStats` by default).
    """

    def __init__(self, registry: MessageRegistry, *, key: str | bytes | None = None,
                 cipher: int | str = TEAM_CIPHER, frame_version: int = FRAME_V2,
                 max_frame: int | None = None, stats: S.DropStats | None = None,
                 iv_source: Callable[[int], bytes] = os.urandom):
        if frame_version not in (FRAME_V1, FRAME_V2):
            raise ValueError(f"frame version must be 1 or 2, not {frame_version}")
        self.registry = registry
        self.frame_version = frame_version
        self.max_frame = max_frame
        self.stats = stats if stats is not None else S.DropStats()
        self._iv_source = iv_source
        self.crypto: FrameCrypto | None = None
        if key is not None:
            self.set_crypto(key, cipher)

    # -- crypto switch -----------------------------------------------------
    def set_crypto(self, key: str | bytes, cipher: int | str = TEAM_CIPHER) -> None:
        """Encrypt from now on with ``key`` (and expect encrypted frames)."""
        if self.frame_version == FRAME_V1:
            raise ValueError("frame header v1 carries no encryption")
        self.crypto = FrameCrypto(key, cipher, self._iv_source)

    def clear_crypto(self) -> None:
        """Send and expect plain frames from now on."""
        self.crypto = None

    @property
    def encrypted(self) -> bool:
        return self.crypto is not None

    # -- send side ----------------------------------------------------------
    def encode(self, msg) -> bytes:
        """The v2 frame for ``msg``.  Raises :class:`~rll_bt.comm.errors.NoCompType`,
        :class:`~rll_bt.comm.errors.FrameTooLarge`, or protobuf's EncodeError when a
        required field is unset."""
        if self.frame_version != FRAME_V2:
            raise ValueError("frame header v1 is decode-only; encode with a v2 codec")
        comp_id, msg_type = require_comp_type(msg)
        body = msg.SerializeToString()
        if self.crypto is None:
            frame = plain_frame(comp_id, msg_type, body)
        else:
            plaintext = MessageHeader(comp_id, msg_type).pack() + body
            frame = encrypted_frame(self.crypto.cipher, self.crypto.encrypt(plaintext))
        if self.max_frame is not None and len(frame) > self.max_frame:
            raise FrameTooLarge(msg.DESCRIPTOR.name, len(frame), self.max_frame, self.encrypted)
        return frame

    def message_bytes(self, msg) -> bytes:
        """Message header + protobuf of ``msg``: what a secured link seals."""
        comp_id, msg_type = require_comp_type(msg)
        return MessageHeader(comp_id, msg_type).pack() + msg.SerializeToString()

    def plain_frame(self, message: bytes) -> bytes:
        """A plain v2 frame around :meth:`message_bytes` (what a tap of a secured link sees)."""
        mh = MessageHeader.unpack(message)
        return plain_frame(mh.comp_id, mh.msg_type, message[4:])

    # -- receive side -------------------------------------------------------
    def decode_message(self, message: bytes, cipher: int) -> tuple[Decoded | None, str | None]:
        """The message in ``message`` (message header + protobuf, opened by a
        secured link) or ``(None, cause)``, counted like :meth:`try_decode`."""
        try:
            mh = MessageHeader.unpack(message)
            return self._parse(mh.comp_id, mh.msg_type, message[4:], cipher), None
        except Drop as drop:
            self.stats.add(drop.cause, drop.detail)
            return None, drop.cause

    def decode(self, frame: bytes) -> Decoded | None:
        """The message in ``frame`` or None (the drop is counted).  Never raises."""
        return self.try_decode(frame)[0]

    def try_decode(self, frame: bytes) -> tuple[Decoded | None, str | None]:
        """``(decoded, None)`` or ``(None, cause)``; the drop is counted.  Never raises."""
        try:
            return self._decode(bytes(frame)), None
        except Drop as drop:
            self.stats.add(drop.cause, drop.detail)
            return None, drop.cause
        except Exception as exc:
            self.stats.add(S.PARSE_ERROR, f"{type(exc).__name__}: {exc}")
            return None, S.PARSE_ERROR

    def _decode(self, frame: bytes) -> Decoded:
        if self.max_frame is not None and len(frame) > self.max_frame:
            raise Drop(S.OVERSIZE, f"{len(frame)} bytes > {self.max_frame}")
        if self.frame_version == FRAME_V1:
            h1 = FrameHeaderV1.unpack(frame)
            if len(frame) != FRAME_HEADER_SIZE + h1.payload_size:
                raise Drop(S.SIZE_MISMATCH, f"v1 frame of {len(frame)} bytes, header says "
                                            f"8 + {h1.payload_size}")
            return self._parse(h1.comp_id, h1.msg_type, frame[FRAME_HEADER_SIZE:], 0)
        hdr = FrameHeader.unpack(frame)
        if hdr.cipher == 0:
            if self.crypto is not None:
                raise Drop(S.PLAIN_ON_ENCRYPTED, "plain frame on an encrypted channel")
            if len(frame) != FRAME_HEADER_SIZE + hdr.payload_size:
                raise Drop(S.SIZE_MISMATCH, f"frame of {len(frame)} bytes, header says "
                                            f"8 + {hdr.payload_size}")
            payload = frame[FRAME_HEADER_SIZE:]
        else:
            if hdr.cipher not in CIPHERS:
                raise Drop(S.BAD_CIPHER, f"cipher id {hdr.cipher}")
            if self.crypto is None:
                raise Drop(S.ENCRYPTED_ON_PLAIN, f"cipher {hdr.cipher} frame, no key set")
            try:
                payload = self.crypto.decrypt(hdr.cipher, frame[FRAME_HEADER_SIZE:])
            except Exception as exc:
                raise Drop(S.DECRYPT_FAILURE, str(exc)) from None
        mh = MessageHeader.unpack(payload)
        return self._parse(mh.comp_id, mh.msg_type, payload[4:], hdr.cipher)

    def _parse(self, comp_id: int, msg_type: int, body: bytes, cipher: int) -> Decoded:
        cls = self.registry.lookup(comp_id, msg_type)
        if cls is None:
            raise Drop(S.UNKNOWN_TYPE, f"COMP_ID {comp_id} MSG_TYPE {msg_type}")
        msg = cls()
        try:
            msg.ParseFromString(body)
        except Exception as exc:
            raise Drop(S.PARSE_ERROR, f"{cls.DESCRIPTOR.name}: {exc}") from None
        if not msg.IsInitialized():
            missing = ", ".join(msg.FindInitializationErrors())
            raise Drop(S.PARSE_ERROR, f"{cls.DESCRIPTOR.name} lacks required {missing}")
        return Decoded(msg, comp_id, msg_type, cipher)
