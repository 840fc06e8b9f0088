"""Normal form of a compiled ``FileDescriptorSet``.

Different protoc releases describe the same ``.proto`` with small variations
that carry no meaning for the wire format: some write ``syntax: "proto2"``
(or an ``edition``) where others leave it out, they may or may not fill in
the default ``json_name`` of every field, and the order of files can differ.
:func:`normalise` removes these, so two protoc versions give byte-identical
output and the staleness check does not flap when CI installs a newer
grpcio-tools.
"""
from __future__ import annotations

from google.protobuf import descriptor_pb2


def default_json_name(field_name: str) -> str:
    """protoc's default JSON name: drop ``_`` and upper-case the next letter."""
    out: list[str] = []
    upper_next = False
    for ch in field_name:
        if ch == "_":
            upper_next = True
        elif upper_next:
            out.append(ch.upper())
            upper_next = False
        else:
            out.append(ch)
    return "".join(out)


def _strip_message(msg: descriptor_pb2.DescriptorProto) -> None:
    for field in list(msg.field) + list(msg.extension):
        if field.HasField("json_name") and field.json_name == default_json_name(field.name):
            field.ClearField("json_name")
    for nested in msg.nested_type:
        _strip_message(nested)


def _strip_file(fdp: descriptor_pb2.FileDescriptorProto) -> None:
    fdp.ClearField("source_code_info")
    if fdp.syntax == "proto2":
        fdp.ClearField("syntax")
    if "edition" in fdp.DESCRIPTOR.fields_by_name and fdp.HasField("edition") \
            and fdp.syntax in ("", "proto2", "proto3"):
        fdp.ClearField("edition")
    for msg in fdp.message_type:
        _strip_message(msg)
    for field in fdp.extension:
        if field.HasField("json_name") and field.json_name == default_json_name(field.name):
            field.ClearField("json_name")


def dependency_order(files) -> list:
    """Files sorted so that each comes after its dependencies; ties by name."""
    by_name = {f.name: f for f in files}
    done: set[str] = set()
    ordered = []

    def visit(name: str, stack: tuple[str, ...]) -> None:
        if name in done or name not in by_name:
            return
        if name in stack:
            raise ValueError("import cycle: " + " -> ".join(stack + (name,)))
        for dep in sorted(by_name[name].dependency):
            visit(dep, stack + (name,))
        done.add(name)
        ordered.append(by_name[name])

    for name in sorted(by_name):
        visit(name, ())
    return ordered


def normalise(fds: descriptor_pb2.FileDescriptorSet) -> descriptor_pb2.FileDescriptorSet:
    """A copy of ``fds`` in normal form (see the module docstring)."""
    out = descriptor_pb2.FileDescriptorSet()
    for fdp in dependency_order(fds.file):
        copy = out.file.add()
        copy.CopyFrom(fdp)
        _strip_file(copy)
    return out


def normalise_bytes(serialized: bytes) -> bytes:
    """Parse a serialized ``FileDescriptorSet`` and return its normal form, serialized."""
    fds = descriptor_pb2.FileDescriptorSet()
    fds.ParseFromString(serialized)
    return normalise(fds).SerializeToString(deterministic=True)


def differing_files(a: bytes, b: bytes) -> list[str]:
    """Names of files whose descriptors differ between two serialized sets."""
    sa, sb = descriptor_pb2.FileDescriptorSet(), descriptor_pb2.FileDescriptorSet()
    sa.ParseFromString(a)
    sb.ParseFromString(b)
    fa = {f.name: f for f in normalise(sa).file}
    fb = {f.name: f for f in normalise(sb).file}
    return sorted(n for n in set(fa) | set(fb) if fa.get(n) != fb.get(n))
