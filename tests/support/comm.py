"""Test-only protobuf messages for the rll_bt.comm tests, built with
descriptor_pb2 in a private DescriptorPool (independent of rll_bt.msgs).

Hello (2000/1), Other (2000/2), TeamCmd (5000/10) are what :func:`registry` accepts;
Stranger (2000/99) has a CompType but is not registered; NoType has none; Clash (another
pool) claims Hello's (2000, 1).

``hand_key``/``pkcs7``/``aes`` redo the refbox crypto from hashlib and raw AES."""
from __future__ import annotations

import hashlib
import socket
import types

from cryptography.hazmat.primitives.ciphers import Cipher, algorithms, modes
from google.protobuf import descriptor_pb2, descriptor_pool, message_factory

F = descriptor_pb2.FieldDescriptorProto


def _msg(fdp, name, fields, comp_type=None):
    m = fdp.message_type.add(name=name)
    for fname, number, ftype, label in fields:
        m.field.add(name=fname, number=number, type=ftype, label=label)
    if comp_type is not None:
        e = m.enum_type.add(name="CompType")
        e.value.add(name="COMP_ID", number=comp_type[0])
        e.value.add(name="MSG_TYPE", number=comp_type[1])


def build_test_messages():
    fdp = descriptor_pb2.FileDescriptorProto(name="commtest.proto", package="commtest",
                                             syntax="proto2")
    _msg(fdp, "Hello", [("name", 1, F.TYPE_STRING, F.LABEL_REQUIRED),
                        ("value", 2, F.TYPE_UINT32, F.LABEL_OPTIONAL),
                        ("blob", 3, F.TYPE_BYTES, F.LABEL_OPTIONAL)], (2000, 1))
    _msg(fdp, "Other", [("x", 1, F.TYPE_INT32, F.LABEL_OPTIONAL),
                        ("tags", 2, F.TYPE_STRING, F.LABEL_REPEATED)], (2000, 2))
    _msg(fdp, "Stranger", [("s", 1, F.TYPE_STRING, F.LABEL_OPTIONAL)], (2000, 99))
    _msg(fdp, "TeamCmd", [("robot", 1, F.TYPE_UINT32, F.LABEL_REQUIRED),
                          ("text", 2, F.TYPE_STRING, F.LABEL_OPTIONAL)], (5000, 10))
    _msg(fdp, "NoType", [("s", 1, F.TYPE_STRING, F.LABEL_OPTIONAL)])
    pool = descriptor_pool.DescriptorPool()
    pool.Add(fdp)
    ns = types.SimpleNamespace()
    for name in ("Hello", "Other", "Stranger", "TeamCmd", "NoType"):
        setattr(ns, name, message_factory.GetMessageClass(
            pool.FindMessageTypeByName(f"commtest.{name}")))
    clash = descriptor_pb2.FileDescriptorProto(name="clash.proto", package="clash",
                                               syntax="proto2")
    _msg(clash, "Clash", [("s", 1, F.TYPE_STRING, F.LABEL_OPTIONAL)], (2000, 1))
    pool2 = descriptor_pool.DescriptorPool()
    pool2.Add(clash)
    ns.Clash = message_factory.GetMessageClass(pool2.FindMessageTypeByName("clash.Clash"))
    return ns


TM = build_test_messages()


def registry():
    from rll_bt.comm import MessageRegistry
    return MessageRegistry([TM.Hello, TM.Other, TM.TeamCmd])


# -- crypto done by hand, independently of rll_bt.comm.crypto ------------------------------

def hand_key(key: str, nbytes: int) -> bytes:
    d = hashlib.sha256(key.encode()).digest()
    for _ in range(7):
        d = hashlib.sha256(d).digest()
    return d[:nbytes]


def pkcs7(data: bytes) -> bytes:
    n = 16 - len(data) % 16
    return data + bytes([n]) * n


def aes(key: bytes, iv: bytes | None, data: bytes, decrypt=False) -> bytes:
    c = Cipher(algorithms.AES(key), modes.CBC(iv) if iv else modes.ECB())
    op = c.decryptor() if decrypt else c.encryptor()
    return op.update(data) + op.finalize()


def free_udp_ports(n):
    """``n`` distinct UDP ports free on 127.0.0.1 right now."""
    socks = [socket.socket(socket.AF_INET, socket.SOCK_DGRAM) for _ in range(n)]
    for s in socks:
        s.bind(("127.0.0.1", 0))
    ports = [s.getsockname()[1] for s in socks]
    for s in socks:
        s.close()
    return ports
