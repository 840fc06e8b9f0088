"""The building blocks of the Robotino 3 base tags: :class:`Tag`, :class:`RawTag`,
the layout helpers and the shapes every tag of the table takes (a request
without data, a struct, an array, a text, a flag byte)."""
from __future__ import annotations

import struct
from dataclasses import dataclass, fields
from typing import ClassVar


class TagError(ValueError):
    """A value does not fit its tag's layout."""


@dataclass(frozen=True)
class Tag:
    """Base of all tags.  Subclasses set ``ID``."""
    ID: ClassVar[int] = -1

    def data(self) -> bytes:
        return b""

    @classmethod
    def from_data(cls, data: bytes) -> Tag:
        return cls()

    def encode(self) -> bytes:
        d = self.data()
        if len(d) > 255:
            raise TagError(f"{type(self).__name__}: {len(d)} data bytes do not fit a tag")
        return bytes((self.ID, len(d))) + d


@dataclass(frozen=True)
class RawTag(Tag):
    """A tag this module does not type (unknown id or unexpected layout)."""
    tag_id: int = 0
    raw: bytes = b""
    reason: str = ""
    truncated: bool = False

    def data(self) -> bytes:
        return bytes(self.raw)

    def encode(self) -> bytes:
        return bytes((self.tag_id, len(self.raw))) + bytes(self.raw)


# -- layout helpers -----------------------------------------------------------

def pack(fmt: str, *values) -> bytes:
    try:
        return struct.pack(fmt, *values)
    except (struct.error, OverflowError, TypeError) as exc:
        raise TagError(f"cannot pack {values!r} as {fmt!r}: {exc}") from None


def unpack(fmt: str, data: bytes) -> tuple:
    if len(data) != struct.calcsize(fmt):
        raise TagError(f"expected {struct.calcsize(fmt)} data bytes, got {len(data)}")
    return struct.unpack(fmt, data)


def unpack_head(fmt: str, data: bytes) -> tuple[tuple, bytes]:
    """Unpack a fixed head and return it with the variable rest."""
    size = struct.calcsize(fmt)
    if len(data) < size:
        raise TagError(f"expected at least {size} data bytes, got {len(data)}")
    return struct.unpack_from(fmt, data), bytes(data[size:])


def latin1(data: bytes) -> str:
    return bytes(data).decode("latin-1")


def ascii_bytes(text: str) -> bytes:
    try:
        return text.encode("latin-1")
    except UnicodeEncodeError as exc:
        raise TagError(f"text {text!r} is not 8-bit: {exc}") from None


@dataclass(frozen=True)
class Request(Tag):
    """A tag without data (a GET).  The firmware ignores data sent with one."""


@dataclass(frozen=True)
class Struct(Tag):
    """Fields map one to one onto the struct format ``FMT``."""
    FMT: ClassVar[str] = "<"

    def data(self) -> bytes:
        return pack(self.FMT, *(getattr(self, f.name) for f in fields(self)))

    @classmethod
    def from_data(cls, data: bytes):
        return cls(*unpack(cls.FMT, data))


@dataclass(frozen=True)
class Array(Tag):
    """One tuple field ``values`` packed as ``FMT`` (e.g. ``"<9f"``)."""
    FMT: ClassVar[str] = "<"
    values: tuple = ()

    def data(self) -> bytes:
        return pack(self.FMT, *self.values)

    @classmethod
    def from_data(cls, data: bytes):
        return cls(tuple(unpack(cls.FMT, data)))


@dataclass(frozen=True)
class Text(Tag):
    text: str = ""

    def data(self) -> bytes:
        return ascii_bytes(self.text)

    @classmethod
    def from_data(cls, data: bytes):
        return cls(latin1(data))


@dataclass(frozen=True)
class Flag(Struct):
    """A single unsigned byte."""
    FMT: ClassVar[str] = "<B"
    value: int = 0
