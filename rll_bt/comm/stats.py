"""Counting frames a receiver drops.

Every dropped or undecodable frame is counted by cause and logged once per
cause (at WARNING, with the first frame's details); the receive path never
raises.  The causes are the :data:`CAUSES` strings.
"""
from __future__ import annotations

import logging
import threading

log = logging.getLogger("rll_bt.comm")

TOO_SHORT = "too_short"              #: shorter than the headers it must carry
BAD_VERSION = "bad_version"          #: frame header version is not 2
BAD_CIPHER = "bad_cipher"            #: cipher id not in 0..4
SIZE_MISMATCH = "size_mismatch"      #: plain frame length != 8 + payload_size
OVERSIZE = "oversize"                #: over the channel's frame limit
PLAIN_ON_ENCRYPTED = "plain_on_encrypted"    #: plain frame, crypto is on
ENCRYPTED_ON_PLAIN = "encrypted_on_plain"    #: encrypted frame, crypto is off
DECRYPT_FAILURE = "decrypt_failure"  #: bad ciphertext length or padding (wrong key)
UNKNOWN_TYPE = "unknown_type"        #: (comp_id, msg_type) not registered
PARSE_ERROR = "parse_error"          #: protobuf did not parse or lacks required fields
STREAM_BROKEN = "stream_broken"      #: a stream frame header made the stream unusable
HANDSHAKE = "handshake"              #: secured link: a bad, missing or repeated hello
AUTH_FAILURE = "auth_failure"        #: secured link: the tag did not check (altered, or wrong key)
REPLAY = "replay"                    #: secured link: a sequence number seen before

CAUSES = (TOO_SHORT, BAD_VERSION, BAD_CIPHER, SIZE_MISMATCH, OVERSIZE, PLAIN_ON_ENCRYPTED,
          ENCRYPTED_ON_PLAIN, DECRYPT_FAILURE, UNKNOWN_TYPE, PARSE_ERROR, STREAM_BROKEN, HANDSHAKE,
          AUTH_FAILURE, REPLAY)

#: causes that mean "this peer does not share our key or crypto setting"
CRYPTO_CAUSES = frozenset({PLAIN_ON_ENCRYPTED, ENCRYPTED_ON_PLAIN, DECRYPT_FAILURE, BAD_CIPHER,
                           HANDSHAKE, AUTH_FAILURE})


class DropStats:
    """Thread-safe counts of dropped frames by cause.

    ``name`` prefixes the log line (e.g. ``"team udp :4441"``).  ``own`` counts
    a UDP peer's own datagrams coming back, which are dropped silently.
    """

    def __init__(self, name: str = "comm"):
        self.name = name
        self._counts: dict[str, int] = {}
        self._lock = threading.Lock()
        self.own = 0

    def add(self, cause: str, detail: str = "") -> None:
        with self._lock:
            n = self._counts.get(cause, 0) + 1
            self._counts[cause] = n
        if n == 1:
            log.warning("%s: dropped a frame (%s)%s; further drops of this kind are only counted",
                        self.name, cause, f": {detail}" if detail else "")

    def count(self, cause: str) -> int:
        with self._lock:
            return self._counts.get(cause, 0)

    def as_dict(self) -> dict[str, int]:
        with self._lock:
            return dict(self._counts)

    @property
    def total(self) -> int:
        with self._lock:
            return sum(self._counts.values())

    def summary(self) -> str:
        """One line, e.g. ``"team: 3 dropped (decrypt_failure 2, unknown_type 1)"``."""
        counts = self.as_dict()
        if not counts:
            return f"{self.name}: no frames dropped"
        parts = ", ".join(f"{c} {n}" for c, n in sorted(counts.items(), key=lambda kv: -kv[1]))
        return f"{self.name}: {sum(counts.values())} dropped ({parts})"
