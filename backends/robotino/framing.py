"""Framing of the Robotino 3 base's "direct" serial protocol.

A frame on the wire (both directions)::

    0xAA | L (uint16 LE) | payload (L bytes of tags) | checksum (uint16 LE)

* ``L`` counts the *unescaped* payload bytes.
* checksum = ``(0x10000 - sum) & 0xFFFF`` where ``sum`` adds the two length
  bytes and every payload byte (unescaped, as unsigned bytes).
* After the head, every length, payload and checksum byte equal to 0xAA or
  0x55 is sent as ``0x55, byte ^ 0x20`` (0xAA -> 55 8A, 0x55 -> 55 75).

:class:`FrameDecoder` is a streaming receiver with the same resync rules as
the base firmware's receiver: an unescaped 0xAA while reading length, payload
or checksum restarts the frame at the length field; ``L > 512`` is rejected
(back to hunting for a head); a checksum mismatch drops the frame.  It never
raises on any input.
"""
from __future__ import annotations

from dataclasses import dataclass

HEAD = 0xAA
ESCAPE = 0x55
MANGLE = 0x20
MAX_PAYLOAD = 512          # the firmware receiver's limit (COM_PAYLOAD_MAX_LENGTH)
MAX_TX_PAYLOAD = 1024 - 5 - 4   # what the firmware's 1024-byte tx buffer can hold (escaped)


class FrameError(ValueError):
    """A byte string is not one well-formed frame."""


def checksum(length_and_payload: bytes) -> int:
    """The frame checksum over the (unescaped) length bytes and payload."""
    return (0x10000 - (sum(length_and_payload) & 0xFFFF)) & 0xFFFF


def stuff(data: bytes) -> bytes:
    """Escape 0xAA and 0x55 (everything after the head goes through this)."""
    if HEAD not in data and ESCAPE not in data:
        return bytes(data)
    out = bytearray()
    for b in data:
        if b in (HEAD, ESCAPE):
            out.append(ESCAPE)
            out.append(b ^ MANGLE)
        else:
            out.append(b)
    return bytes(out)


def unstuff(data: bytes) -> bytes:
    """Undo :func:`stuff`.  A trailing lone escape byte is dropped."""
    out = bytearray()
    escaped = False
    for b in data:
        if escaped:
            out.append(b ^ MANGLE)
            escaped = False
        elif b == ESCAPE:
            escaped = True
        else:
            out.append(b)
    return bytes(out)


def encode_frame(payload: bytes) -> bytes:
    """A complete, escaped frame carrying ``payload`` (a concatenation of tags)."""
    n = len(payload)
    if n > 0xFFFF:
        raise FrameError(f"payload of {n} bytes does not fit a 16-bit length")
    body = bytes((n & 0xFF, n >> 8)) + bytes(payload)
    c = checksum(body)
    return bytes((HEAD,)) + stuff(body + bytes((c & 0xFF, c >> 8)))


def decode_frame(frame: bytes) -> bytes:
    """The payload of exactly one complete frame; :class:`FrameError` otherwise."""
    if not frame or frame[0] != HEAD:
        raise FrameError("frame does not start with the 0xAA head")
    if HEAD in frame[1:]:
        raise FrameError("unescaped 0xAA inside the frame")
    if frame[-1] == ESCAPE:
        raise FrameError("frame ends in an escape byte")
    body = unstuff(frame[1:])
    if len(body) < 4:
        raise FrameError(f"frame too short ({len(body)} unescaped bytes after the head)")
    n = body[0] | body[1] << 8
    if len(body) != n + 4:
        raise FrameError(f"length field says {n} payload bytes, frame holds {len(body) - 4}")
    got = body[-2] | body[-1] << 8
    want = checksum(body[:-2])
    if got != want:
        raise FrameError(f"checksum mismatch: frame has {got:#06x}, computed {want:#06x}")
    return body[2:-2]


# -- streaming receiver ------------------------------------------------------

@dataclass(frozen=True)
class Frame:
    """A frame that passed the checksum."""
    payload: bytes


@dataclass(frozen=True)
class ChecksumMismatch:
    """A frame dropped for its checksum: ``received`` is the value on the wire,
    ``computed`` the one the receiver expected (the firmware prints them as
    ``RX checksum mismatch <received> <computed>`` in lower-case hex)."""
    received: int
    computed: int
    payload: bytes


@dataclass(frozen=True)
class Oversize:
    """A length field above :data:`MAX_PAYLOAD`; the receiver hunts for a new head."""
    length: int


_WAIT_HEAD, _LENGTH, _PAYLOAD, _CHECKSUM = range(4)


class FrameDecoder:
    """Streaming receiver mirroring the base firmware's state machine.

    :meth:`feed` takes any bytes and returns the events they complete
    (:class:`Frame`, :class:`ChecksumMismatch`, :class:`Oversize`).  The
    counters ``frames``, ``checksum_errors``, ``oversize`` and ``restarts``
    (unescaped heads inside a frame) only grow, until :meth:`reset_counters`.
    ``max_payload`` may be raised to receive the base's longer replies.
    """

    def __init__(self, max_payload: int = MAX_PAYLOAD):
        self.max_payload = max_payload
        self.frames = 0
        self.checksum_errors = 0
        self.oversize = 0
        self.restarts = 0
        self.reset()

    def reset(self) -> None:
        """Forget any partial frame and hunt for the next head."""
        self._state = _WAIT_HEAD
        self._escaped = False
        self._buf = bytearray()
        self._need = 0
        self._length = 0

    def reset_counters(self) -> None:
        self.frames = self.checksum_errors = self.oversize = self.restarts = 0

    @property
    def in_frame(self) -> bool:
        """True between a head and the end of its frame."""
        return self._state != _WAIT_HEAD

    def _start(self) -> None:
        self._state = _LENGTH
        self._escaped = False
        self._buf = bytearray()
        self._need = 2

    def feed(self, data: bytes) -> list:
        events: list = []
        for b in data:
            if self._state == _WAIT_HEAD:
                if b == HEAD:
                    self._start()
                continue
            if self._escaped:
                self._escaped = False
                self._buf.append(b ^ MANGLE)
            elif b == ESCAPE:
                self._escaped = True
                continue
            elif b == HEAD:
                self.restarts += 1
                self._start()
                continue
            else:
                self._buf.append(b)
            if len(self._buf) < self._need:
                continue
            self._advance(events)
        return events

    def _advance(self, events: list) -> None:
        self._escaped = False
        if self._state == _LENGTH:
            self._length = self._buf[0] | self._buf[1] << 8
            if self._length > self.max_payload:
                self.oversize += 1
                events.append(Oversize(self._length))
                self.reset()
                return
            self._state = _PAYLOAD
            self._need = 2 + self._length
            if self._length == 0:
                self._state = _CHECKSUM
                self._need = 4
        elif self._state == _PAYLOAD:
            self._state = _CHECKSUM
            self._need = 4 + self._length
        else:
            body = bytes(self._buf)
            got = body[-2] | body[-1] << 8
            want = checksum(body[:-2])
            payload = body[2:-2]
            if got == want:
                self.frames += 1
                events.append(Frame(payload))
            else:
                self.checksum_errors += 1
                events.append(ChecksumMismatch(got, want, payload))
            self.reset()
