"""The message registry: protobuf classes keyed by their ``CompType`` enum.

Every refbox message has a nested ``enum CompType { COMP_ID = ...; MSG_TYPE = ...; }``;
``(COMP_ID, MSG_TYPE)`` is what the 4-byte message header carries.  A frame
whose pair is not registered is dropped by the receiver.
"""
from __future__ import annotations

from collections.abc import Iterable, Mapping

from ..msgs.messageset import comp_type_of  # one definition, shared with the message sets
from .errors import NoCompType, RegistryConflict

CompType = tuple[int, int]


def require_comp_type(cls_or_msg) -> CompType:
    ct = comp_type_of(cls_or_msg)
    if ct is None:
        name = getattr(getattr(cls_or_msg, "DESCRIPTOR", None), "full_name", repr(cls_or_msg))
        raise NoCompType(f"{name} has no nested enum CompType {{COMP_ID; MSG_TYPE}}, "
                         "so it cannot be framed")
    return ct


class MessageRegistry:
    """Maps ``(comp_id, msg_type)`` to a protobuf message class.

    ``MessageRegistry(classes)`` registers every class that has a
    ``CompType``; classes without one (e.g. ``Time``) are skipped.
    """

    def __init__(self, classes: Iterable[type] = ()):
        self._by_ct: dict[CompType, type] = {}
        self.add_all(classes)

    @classmethod
    def from_message_set(cls, *sets) -> MessageRegistry:
        """Registry of one or more :mod:`rll_bt.msgs` message sets (anything with ``.classes``)."""
        reg = cls()
        for ms in sets:
            classes = getattr(ms, "classes", ms)
            reg.add_all(classes.values() if isinstance(classes, Mapping) else classes)
        return reg

    def add(self, cls: type) -> CompType:
        """Register ``cls``; :class:`NoCompType` without CompType, :class:`RegistryConflict`
        if another class already holds its pair."""
        ct = require_comp_type(cls)
        have = self._by_ct.get(ct)
        if have is not None and have is not cls:
            raise RegistryConflict(f"{cls.DESCRIPTOR.full_name} and {have.DESCRIPTOR.full_name} "
                                   f"both claim COMP_ID {ct[0]} MSG_TYPE {ct[1]}")
        self._by_ct[ct] = cls
        return ct

    def add_all(self, classes: Iterable[type]) -> int:
        """Register those of ``classes`` that have a CompType; returns how many."""
        n = 0
        for c in classes:
            if not hasattr(c, "DESCRIPTOR"):
                raise TypeError(f"not a protobuf message class: {c!r}")
            if comp_type_of(c) is not None:
                self.add(c)
                n += 1
        return n

    def lookup(self, comp_id: int, msg_type: int) -> type | None:
        return self._by_ct.get((comp_id, msg_type))

    def by_name(self, name: str) -> type | None:
        """The registered class whose short or full name is ``name``."""
        for cls in self._by_ct.values():
            if name in (cls.DESCRIPTOR.name, cls.DESCRIPTOR.full_name):
                return cls
        return None

    def __contains__(self, key) -> bool:
        if isinstance(key, tuple):
            return key in self._by_ct
        return comp_type_of(key) in self._by_ct and self._by_ct[comp_type_of(key)] is key

    def __len__(self) -> int:
        return len(self._by_ct)

    def __iter__(self):
        return iter(self._by_ct.items())
