"""Read the refbox's stored games: a MongoDB archive of game reports.

The refbox keeps each game's report (field, orders, ring costs, machine
history, points) as a document of its MongoDB collection
``rcll.game_report``; its repository ships a hundred of them as
``benchmarks/rcll100.gz``, a ``mongodump --archive --gzip`` file.  That
format (MongoDB's archive format, version 0.1):

- optional gzip around everything;
- the magic number 0x8199E26D (little-endian uint32);
- a header BSON document (``version``, ``server_version``, ...);
- one BSON metadata document per collection (``db``, ``collection``,
  ``metadata`` as JSON text, ``size``), then a terminator (int32 -1);
- blocks: a namespace header document (``db``, ``collection``, ``EOF``,
  ``CRC``), then either the block's BSON documents and a terminator, or, for
  ``EOF: true``, nothing more for that collection.

BSON is decoded with pymongo's ``bson`` (a dependency of the ``games`` extra).
"""
from __future__ import annotations

import gzip
import struct
from collections.abc import Iterator

MAGIC = 0x8199E26D
TERMINATOR = -1


class ArchiveError(ValueError):
    """The file is not a MongoDB archive this reader understands."""


def _bson():
    try:
        import bson
    except ImportError:
        raise ArchiveError("reading refbox archives needs pymongo's bson "
                           "(pip install 'rll-bt[games]')") from None
    return bson


class _Reader:
    def __init__(self, data: bytes, name: str):
        self.data, self.pos, self.name = data, 0, name
        self.bson = _bson()

    def int32(self) -> int:
        if self.pos + 4 > len(self.data):
            raise ArchiveError(f"{self.name}: truncated at byte {self.pos}")
        (n,) = struct.unpack_from("<i", self.data, self.pos)
        return n

    def doc(self) -> dict | None:
        """The next BSON document, None for a terminator."""
        n = self.int32()
        if n == TERMINATOR:
            self.pos += 4
            return None
        if n < 5 or self.pos + n > len(self.data):
            raise ArchiveError(f"{self.name}: bad document length {n} at byte {self.pos}")
        try:
            d = self.bson.decode(self.data[self.pos:self.pos + n])
        except Exception as e:
            raise ArchiveError(f"{self.name}: bad BSON at byte {self.pos}: {e}") from None
        self.pos += n
        return d


def read_archive(path_or_bytes, name: str | None = None) -> Iterator[tuple[str, str, dict]]:
    """Every document of a MongoDB archive as (db, collection, document)."""
    if isinstance(path_or_bytes, (bytes, bytearray)):
        raw, name = bytes(path_or_bytes), name or "archive"
    else:
        name = name or str(path_or_bytes)
        try:
            with open(path_or_bytes, "rb") as f:
                raw = f.read()
        except OSError as e:
            raise ArchiveError(f"{name}: {e.strerror or e}") from None
    if raw[:2] == b"\x1f\x8b":
        try:
            raw = gzip.decompress(raw)
        except (OSError, EOFError) as e:
            raise ArchiveError(f"{name}: bad gzip data: {e}") from None
    if len(raw) < 4 or struct.unpack_from("<I", raw)[0] != MAGIC:
        raise ArchiveError(f"{name}: not a MongoDB archive (no magic number)")
    r = _Reader(raw, name)
    r.pos = 4
    header = r.doc()
    if header is None or "version" not in header:
        raise ArchiveError(f"{name}: no archive header")
    while r.doc() is not None:               # collection metadata up to the terminator
        pass
    while r.pos < len(raw):
        ns = r.doc()
        if ns is None:
            continue
        if "db" not in ns or "collection" not in ns:
            raise ArchiveError(f"{name}: block without a namespace header at byte {r.pos}")
        if ns.get("EOF"):
            continue
        while (d := r.doc()) is not None:
            yield ns["db"], ns["collection"], d


def game_reports(path_or_bytes) -> list[dict]:
    """The refbox's game reports (collection ``game_report``) of an archive."""
    return [d for _, coll, d in read_archive(path_or_bytes) if coll == "game_report"]


__all__ = ["ArchiveError", "game_reports", "read_archive"]
