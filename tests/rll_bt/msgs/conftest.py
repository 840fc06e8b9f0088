"""Shared helpers for the message-set tests: build messages generically from descriptors."""
from __future__ import annotations

import pytest
from google.protobuf.descriptor import FieldDescriptor as FD

_INT_TYPES = {FD.TYPE_INT32, FD.TYPE_SINT32, FD.TYPE_SFIXED32}
_UINT_TYPES = {FD.TYPE_UINT32, FD.TYPE_FIXED32}
_INT64_TYPES = {FD.TYPE_INT64, FD.TYPE_SINT64, FD.TYPE_SFIXED64}
_UINT64_TYPES = {FD.TYPE_UINT64, FD.TYPE_FIXED64}


def is_required(field) -> bool:
    """Label test that works with old (``label``) and new (``is_required``) protobuf."""
    if hasattr(field, "is_required"):
        return field.is_required
    return field.label == FD.LABEL_REQUIRED


def is_repeated(field) -> bool:
    if hasattr(field, "is_repeated"):
        return field.is_repeated
    return field.label == FD.LABEL_REPEATED


def _scalar(field, seed: int):
    t = field.type
    if t in _INT_TYPES:
        return -7 - seed
    if t in _UINT_TYPES:
        return 300 + seed              # two-byte varint
    if t in _INT64_TYPES:
        return -(2 ** 40) - seed
    if t in _UINT64_TYPES:
        return 2 ** 40 + seed
    if t == FD.TYPE_FLOAT:
        return 1.5 + seed              # exact in float32
    if t == FD.TYPE_DOUBLE:
        return 0.1 + seed
    if t == FD.TYPE_BOOL:
        return True
    if t == FD.TYPE_STRING:
        return f"{field.name}-{seed}"
    if t == FD.TYPE_BYTES:
        return bytes([0, 255, seed % 256])
    if t == FD.TYPE_ENUM:
        values = field.enum_type.values
        return values[(seed + len(values) - 1) % len(values)].number  # not the default
    raise AssertionError(f"unhandled type {t} of {field.full_name}")


def fill(msg, mode: str = "all", seed: int = 1, oneof_choice: dict | None = None, depth: int = 0):
    """Fill ``msg`` in place.

    mode "all": every field (repeated ones with two elements; in each oneof
    the member named in ``oneof_choice`` or the first one); mode "required":
    only the required fields, recursively.
    """
    assert depth < 6, "unexpectedly deep message nesting"
    oneof_choice = oneof_choice or {}
    for field in msg.DESCRIPTOR.fields:
        required = is_required(field)
        if mode == "required" and not required:
            continue
        oneof = field.containing_oneof
        if oneof is not None:
            chosen = oneof_choice.get(oneof.full_name, oneof.fields[0].name)
            if field.name != chosen:
                continue
        repeated = is_repeated(field)
        count = 2 if repeated else 1
        for i in range(count):
            s = seed + i
            if field.type == FD.TYPE_MESSAGE:
                target = getattr(msg, field.name).add() if repeated else getattr(msg, field.name)
                fill(target, mode, s, oneof_choice, depth + 1)
                if not repeated:
                    target.SetInParent()
            elif repeated:
                getattr(msg, field.name).append(_scalar(field, s))
            else:
                setattr(msg, field.name, _scalar(field, s))
    return msg


def oneof_variants(descriptor, prefix=()):
    """One ``oneof_choice`` dict per member of every oneof reachable from ``descriptor``."""
    variants = [{}]
    seen = set()

    def walk(desc):
        if desc.full_name in seen:
            return
        seen.add(desc.full_name)
        for oneof in desc.oneofs:
            for member in oneof.fields:
                variants.append({oneof.full_name: member.name})
        for field in desc.fields:
            if field.type == FD.TYPE_MESSAGE:
                walk(field.message_type)

    walk(descriptor)
    return variants


@pytest.fixture
def filler():
    """``fill(msg, mode="all"|"required", seed=1, oneof_choice=None)``."""
    return fill


@pytest.fixture
def variants():
    """``oneof_variants(descriptor)``: one oneof choice per oneof member."""
    return oneof_variants
