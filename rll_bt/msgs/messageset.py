"""A message set: the classes of one ``proto/<set>/`` in a descriptor pool of its own.

Both refbox sets define the same full names (``llsf_msgs.GameState`` ...), so
they cannot share protobuf's default pool.  Each :class:`MessageSet` adds
its embedded ``FileDescriptorSet`` to a fresh
``google.protobuf.descriptor_pool.DescriptorPool`` and builds its classes
through ``google.protobuf.message_factory``; any number of sets coexist in
one process.
"""
from __future__ import annotations

import base64
import importlib
import threading
from collections.abc import Mapping
from types import MappingProxyType

from google.protobuf import descriptor_pb2, descriptor_pool, message_factory
from google.protobuf.internal.enum_type_wrapper import EnumTypeWrapper

from .sources import SETS

CompType = tuple[int, int]


def _message_class(descriptor):
    """The class of ``descriptor`` (protobuf >= 4.22 API, older fallback)."""
    get = getattr(message_factory, "GetMessageClass", None)
    if get is not None:
        return get(descriptor)
    return message_factory.MessageFactory(descriptor.file.pool).GetPrototype(descriptor)  # pragma: no cover


def comp_type_of(cls_or_msg) -> CompType | None:
    """``(COMP_ID, MSG_TYPE)`` of the nested ``enum CompType``; None without one.

    Accepts a message class, a message instance or a message descriptor.
    """
    desc = getattr(cls_or_msg, "DESCRIPTOR", cls_or_msg)
    enum = getattr(desc, "enum_types_by_name", {}).get("CompType")
    if enum is None:
        return None
    values = enum.values_by_name
    if "COMP_ID" not in values or "MSG_TYPE" not in values:
        return None
    return values["COMP_ID"].number, values["MSG_TYPE"].number


class MessageSet:
    """The message classes and enums of one set (``rcll2016``, ``rcll2025`` or ``team``).

    Get one with :func:`rll_bt.msgs.message_set`; see the package docstring.
    """

    def __init__(self, name: str, descriptor_set: bytes, source_sha256: str = ""):
        self.name = name
        self.source_sha256 = source_sha256
        self.descriptor_set = bytes(descriptor_set)
        self.pool = descriptor_pool.DescriptorPool()
        fds = descriptor_pb2.FileDescriptorSet()
        fds.ParseFromString(descriptor_set)
        for fdp in fds.file:
            self.pool.AddSerializedFile(fdp.SerializeToString())
        self.files: tuple[str, ...] = tuple(f.name for f in fds.file)
        self.package: str = fds.file[0].package if fds.file else ""

        all_classes: dict[str, type] = {}
        enums: dict[str, EnumTypeWrapper] = {}
        for file_name in self.files:
            fd = self.pool.FindFileByName(file_name)
            for msg_name, msg_desc in fd.message_types_by_name.items():
                all_classes[msg_name] = _message_class(msg_desc)
            for enum_name, enum_desc in fd.enum_types_by_name.items():
                enums[enum_name] = EnumTypeWrapper(enum_desc)
        self.all_classes: Mapping[str, type] = MappingProxyType(dict(sorted(all_classes.items())))
        self.enums: Mapping[str, EnumTypeWrapper] = MappingProxyType(dict(sorted(enums.items())))

        classes: dict[str, type] = {}
        by_ct: dict[CompType, type] = {}
        for msg_name, cls in self.all_classes.items():
            ct = comp_type_of(cls)
            if ct is None:
                continue
            if ct in by_ct:
                raise ValueError(f"message set {name}: {msg_name} and {by_ct[ct].DESCRIPTOR.name} "
                                 f"share COMP_ID {ct[0]} MSG_TYPE {ct[1]}")
            classes[msg_name] = cls
            by_ct[ct] = cls
        self.classes: Mapping[str, type] = MappingProxyType(classes)
        self.by_comp_type: Mapping[CompType, type] = MappingProxyType(by_ct)

    def file_descriptor_set(self) -> descriptor_pb2.FileDescriptorSet:
        """A fresh copy of the set's descriptors (``descriptor_pb2.FileDescriptorSet``)."""
        fds = descriptor_pb2.FileDescriptorSet()
        fds.ParseFromString(self.descriptor_set)
        return fds

    # -- lookup -------------------------------------------------------------
    def get(self, name: str) -> type:
        """The class of top-level message ``name`` (short or ``package.Name``)."""
        short = name[len(self.package) + 1:] if name.startswith(self.package + ".") else name
        try:
            return self.all_classes[short]
        except KeyError:
            raise KeyError(f"message set {self.name} has no message {name!r}; known: "
                           + ", ".join(self.all_classes)) from None

    def __getattr__(self, name: str):
        # Only called for names that are not regular attributes.
        if name.startswith("_"):
            raise AttributeError(name)
        d = self.__dict__
        if name in d.get("all_classes", {}):
            return d["all_classes"][name]
        if name in d.get("enums", {}):
            return d["enums"][name]
        raise AttributeError(f"message set {d.get('name')} has no message or enum {name!r}")

    def __contains__(self, name: str) -> bool:
        return name in self.all_classes

    def enum(self, name: str) -> EnumTypeWrapper:
        """Enum wrapper (``Name``/``Value``/``keys``/``values``) of a top-level enum,
        or of a nested one as ``"GameState.Phase"``."""
        if name in self.enums:
            return self.enums[name]
        if "." in name:
            outer, inner = name.rsplit(".", 1)
            try:
                desc = self.get(outer).DESCRIPTOR.enum_types_by_name[inner]
            except KeyError:
                pass
            else:
                return EnumTypeWrapper(desc)
        raise KeyError(f"message set {self.name} has no enum {name!r}; top-level enums: "
                       + ", ".join(self.enums))

    def comp_type(self, cls_or_msg) -> CompType | None:
        """``(comp_id, msg_type)`` from the nested ``enum CompType``, or None."""
        return comp_type_of(cls_or_msg)

    def decode(self, comp_id: int, msg_type: int, payload: bytes):
        """Parse ``payload`` as the message registered for ``(comp_id, msg_type)``.

        KeyError when the pair is unknown; protobuf's ``DecodeError`` on bad bytes.
        """
        try:
            cls = self.by_comp_type[(comp_id, msg_type)]
        except KeyError:
            raise KeyError(f"message set {self.name}: no message with COMP_ID {comp_id} "
                           f"MSG_TYPE {msg_type}") from None
        msg = cls()
        msg.ParseFromString(payload)
        return msg

    def __repr__(self) -> str:
        return (f"<MessageSet {self.name}: {len(self.all_classes)} messages, "
                f"{len(self.classes)} with CompType>")


_CACHE: dict[str, MessageSet] = {}
_LOCK = threading.Lock()


def message_set(name: str) -> MessageSet:
    """The (cached) message set ``name``: one of :data:`SETS`.

    ValueError, listing the known names, for any other name.
    """
    if name not in SETS:
        raise ValueError(f"unknown message set {name!r}; known: {', '.join(SETS)}")
    with _LOCK:
        ms = _CACHE.get(name)
        if ms is None:
            module = importlib.import_module(f"{__package__}._gen_{name}")
            data = base64.b64decode("".join(module.DESCRIPTOR_SET_B64))
            ms = MessageSet(name, data, module.SOURCE_SHA256)
            _CACHE[name] = ms
        return ms
