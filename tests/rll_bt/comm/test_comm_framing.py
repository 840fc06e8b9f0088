"""Frame and message headers exactly as refbox-protocol §1, checked with hand-built bytes."""
from __future__ import annotations

import struct

import pytest
from google.protobuf.message import EncodeError

from rll_bt.comm import (
    FRAME_V1,
    FrameCodec,
    FrameHeader,
    FrameTooLarge,
    MessageRegistry,
    NoCompType,
    RegistryConflict,
    StreamReassembler,
    comp_type_of,
)
from rll_bt.comm import stats as S


def hand_plain_frame(comp_id, msg_type, body):
    # [version=2][cipher=0][reserved 0 0][payload_size u32 BE][comp_id u16 BE][msg_type u16 BE][pb]
    return (bytes([2, 0, 0, 0]) + (4 + len(body)).to_bytes(4, "big")
            + comp_id.to_bytes(2, "big") + msg_type.to_bytes(2, "big") + body)


def test_plain_frame_bytes_are_exactly_the_protobuf_comm_layout(tm):
    msg = tm.Hello(name="R1", value=7)
    frame = FrameCodec(tm.registry()).encode(msg)
    assert frame == hand_plain_frame(2000, 1, msg.SerializeToString())
    assert frame[:8] == b"\x02\x00\x00\x00" + struct.pack(">I", 4 + msg.ByteSize())


def test_hand_built_plain_frame_decodes(tm):
    body = tm.Other(x=-3, tags=["a", "b"]).SerializeToString()
    d = FrameCodec(tm.registry()).decode(hand_plain_frame(2000, 2, body))
    assert d is not None and d.comp_id == 2000 and d.msg_type == 2 and d.cipher == 0
    assert d.msg.x == -3 and list(d.msg.tags) == ["a", "b"]


def test_receiver_requires_len_equal_8_plus_payload_size(tm):
    codec = FrameCodec(tm.registry())
    good = hand_plain_frame(2000, 1, tm.Hello(name="x").SerializeToString())
    assert codec.decode(good + b"\x00") is None
    assert codec.decode(good[:-1]) is None
    # payload_size one too large / too small with the bytes unchanged
    size = struct.unpack(">I", good[4:8])[0]
    assert codec.decode(good[:4] + struct.pack(">I", size + 1) + good[8:]) is None
    assert codec.decode(good[:4] + struct.pack(">I", size - 1) + good[8:]) is None
    assert codec.stats.count(S.SIZE_MISMATCH) == 4
    assert codec.decode(good).msg.name == "x"


def test_short_bad_version_unknown_type_and_parse_error_are_counted(tm):
    codec = FrameCodec(tm.registry())
    assert codec.decode(b"\x02\x00\x00") is None
    assert codec.decode(bytes([2, 0, 0, 0, 0, 0, 0, 2, 0x07, 0xD0])) is None  # header of 2 bytes
    v3 = bytearray(hand_plain_frame(2000, 1, tm.Hello(name="x").SerializeToString()))
    v3[0] = 3
    assert codec.decode(bytes(v3)) is None
    stranger = tm.Stranger(s="hi").SerializeToString()
    assert codec.decode(hand_plain_frame(2000, 99, stranger)) is None
    # Hello lacks its required name: the refbox's ParseFromArray fails on this too
    assert codec.decode(hand_plain_frame(2000, 1, tm.Hello().SerializePartialToString())) is None
    assert codec.decode(hand_plain_frame(2000, 1, b"\xff\xff")) is None
    assert codec.decode(bytes([2, 9, 0, 0, 0, 0, 0, 16]) + bytes(16)) is None
    assert codec.stats.as_dict() == {S.TOO_SHORT: 2, S.BAD_VERSION: 1, S.UNKNOWN_TYPE: 1,
                                     S.PARSE_ERROR: 2, S.BAD_CIPHER: 1}
    assert codec.stats.total == 7


def test_each_cause_is_logged_once_and_then_only_counted(tm, caplog):
    codec = FrameCodec(tm.registry())
    stranger = hand_plain_frame(2000, 99, tm.Stranger(s="hi").SerializeToString())
    with caplog.at_level("WARNING", logger="rll_bt.comm"):
        for _ in range(5):
            assert codec.decode(b"\x02\x00") is None
            assert codec.decode(stranger) is None
    lines = [r.getMessage() for r in caplog.records if r.name == "rll_bt.comm"]
    assert len(lines) == 2, lines
    assert sum(S.TOO_SHORT in ln for ln in lines) == 1 and sum(S.UNKNOWN_TYPE in ln for ln in lines) == 1
    assert codec.stats.as_dict() == {S.TOO_SHORT: 5, S.UNKNOWN_TYPE: 5}
    assert codec.stats.summary().endswith("10 dropped (too_short 5, unknown_type 5)") or \
        codec.stats.summary().endswith("10 dropped (unknown_type 5, too_short 5)")


def test_v1_frames_decode(tm):
    body = tm.Hello(name="legacy", value=1).SerializeToString()
    # v1: comp_id u16, msg_type u16, payload_size u32 = len(protobuf), then protobuf
    frame = struct.pack(">HHI", 2000, 1, len(body)) + body
    codec = FrameCodec(tm.registry(), frame_version=FRAME_V1)
    d = codec.decode(frame)
    assert d.msg.name == "legacy" and (d.comp_id, d.msg_type) == (2000, 1)
    assert codec.decode(frame + b"x") is None
    assert codec.stats.count(S.SIZE_MISMATCH) == 1
    with pytest.raises(ValueError):
        codec.encode(tm.Hello(name="x"))
    with pytest.raises(ValueError):
        FrameCodec(tm.registry(), frame_version=FRAME_V1, key="k")


def test_frame_header_roundtrip_and_reserved_bytes():
    h = FrameHeader(cipher=2, payload_size=0x01020304)
    assert h.pack() == b"\x02\x02\x00\x00\x01\x02\x03\x04"
    assert FrameHeader.unpack(h.pack() + b"rest") == h


def test_encode_refuses_missing_comp_type_and_required_fields_and_oversize(tm):
    codec = FrameCodec(tm.registry(), max_frame=1024)
    with pytest.raises(NoCompType):
        codec.encode(tm.NoType(s="x"))
    with pytest.raises(EncodeError):
        codec.encode(tm.Hello())  # required name unset
    # frame = 8 + 4 + pb; pb = (1+1+2 name "ab") + (1+2+n blob): n = 1005 gives exactly 1024
    assert len(codec.encode(tm.Hello(name="ab", blob=b"x" * 1005))) == 1024
    with pytest.raises(FrameTooLarge, match="1025-byte frame, over the 1024-byte limit"):
        codec.encode(tm.Hello(name="ab", blob=b"x" * 1006))


def test_registry_keys_by_comp_type(tm):
    reg = tm.registry()
    assert comp_type_of(tm.Hello) == (2000, 1) and comp_type_of(tm.Hello(name="a")) == (2000, 1)
    assert comp_type_of(tm.NoType) is None
    assert reg.lookup(2000, 1) is tm.Hello and reg.lookup(5000, 10) is tm.TeamCmd
    assert reg.lookup(2000, 99) is None and (2000, 2) in reg and len(reg) == 3
    assert reg.by_name("Other") is tm.Other and reg.by_name("commtest.TeamCmd") is tm.TeamCmd
    # classes without CompType are skipped by add_all, refused by add
    assert MessageRegistry([tm.NoType, tm.Stranger]).lookup(2000, 99) is tm.Stranger
    with pytest.raises(NoCompType):
        reg.add(tm.NoType)


def test_registry_from_message_set_like_objects(tm):
    import types as _t
    from collections import OrderedDict
    ms = _t.SimpleNamespace(classes=_t.MappingProxyType(OrderedDict(Hello=tm.Hello, NoType=tm.NoType)))
    reg = MessageRegistry.from_message_set(ms, [tm.Other])
    assert reg.lookup(2000, 1) is tm.Hello and reg.lookup(2000, 2) is tm.Other and len(reg) == 2
    with pytest.raises(TypeError, match="not a protobuf message class"):
        MessageRegistry(["Hello"])


def test_registry_conflict_is_an_error(tm):
    reg = tm.registry()
    with pytest.raises(RegistryConflict, match="COMP_ID 2000 MSG_TYPE 1"):
        reg.add(tm.Clash)
    reg.add(tm.Hello)  # re-adding the same class is fine
    assert reg.lookup(2000, 1) is tm.Hello


def test_stream_reassembler_cuts_frames_across_chunks(tm):
    codec = FrameCodec(tm.registry())
    frames = [codec.encode(tm.Hello(name=f"n{i}", value=i)) for i in range(5)]
    stream = b"".join(frames)
    r = StreamReassembler()
    out = []
    for i in range(0, len(stream), 3):
        out += r.feed(stream[i:i + 3])
    assert out == frames and r.pending == 0 and r.broken is None


def test_stream_reassembler_breaks_on_bad_version_and_oversize():
    r = StreamReassembler(max_payload=100)
    assert r.feed(b"\x02\x00\x00\x00\x00\x00\x01\x00") == []
    assert r.broken.cause == S.OVERSIZE
    r = StreamReassembler()
    assert r.feed(b"\x05\x00\x00\x00\x00\x00\x00\x04abcd") == []
    assert r.broken.cause == S.BAD_VERSION and r.feed(b"more") == []
