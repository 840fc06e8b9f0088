"""Errors the send path of :mod:`rll_bt.comm` raises.

The receive path never raises: every frame it cannot use is counted in a
:class:`rll_bt.comm.stats.DropStats` instead.
"""
from __future__ import annotations


class CommError(Exception):
    """Base class of the errors a transport raises to its caller."""


class FrameTooLarge(CommError, ValueError):
    """An encoded frame exceeds the transport's limit (1024 B for UDP)."""

    def __init__(self, type_name: str, size: int, limit: int, encrypted: bool):
        how = "encrypted " if encrypted else ""
        super().__init__(
            f"{type_name} encodes to a {how}{size}-byte frame, over the {limit}-byte limit "
            f"of this channel (protobuf_comm's max_packet_length)")
        self.type_name, self.size, self.limit, self.encrypted = type_name, size, limit, encrypted


class NoCompType(CommError, ValueError):
    """A message class lacks the nested ``enum CompType {COMP_ID; MSG_TYPE}``."""


class RegistryConflict(CommError, ValueError):
    """Two different message classes claim the same (comp_id, msg_type)."""


class CryptoError(CommError):
    """A frame could not be decrypted (wrong key, bad length, bad padding)."""
