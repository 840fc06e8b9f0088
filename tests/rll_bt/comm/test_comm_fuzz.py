"""Hypothesis fuzzing of the decoders: random and mutated frames never raise or hang."""
from __future__ import annotations

import socket
import time

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from rll_bt.comm import FRAME_V1, FrameCodec, StreamReassembler, StreamServer, UdpPeer
from tests.support.comm import TM, registry

KEY = "randomkey"
FUZZ = settings(max_examples=250, deadline=None,
                suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture])


CODECS = {
    "plain": lambda: FrameCodec(registry(), max_frame=1024),
    "aes128cbc": lambda: FrameCodec(registry(), key=KEY, max_frame=1024),
    "aes256ecb": lambda: FrameCodec(registry(), key=KEY, cipher=3, max_frame=1024),
    "v1": lambda: FrameCodec(registry(), frame_version=FRAME_V1),
}

messages = st.one_of(
    st.builds(TM.Hello, name=st.text(max_size=30), value=st.integers(0, 2**32 - 1),
              blob=st.binary(max_size=200)),
    st.builds(TM.Other, x=st.integers(-2**31, 2**31 - 1),
              tags=st.lists(st.text(max_size=10), max_size=5)),
)


def check(codec, data):
    before = codec.stats.total
    d = codec.decode(data)
    if d is None:
        assert codec.stats.total == before + 1
    else:
        assert d.msg.IsInitialized() and codec.stats.total == before
    return d


@pytest.mark.parametrize("kind", sorted(CODECS))
@FUZZ
@given(data=st.binary(max_size=1200))
def test_random_bytes(kind, data):
    check(CODECS[kind](), data)


@st.composite
def mutated(draw, key):
    msg = draw(messages)
    cipher = draw(st.sampled_from([1, 2, 3, 4]))
    sender = FrameCodec(registry(), key=key, cipher=cipher) if key else FrameCodec(registry())
    frame = bytearray(sender.encode(msg))
    for _ in range(draw(st.integers(0, 4))):
        op = draw(st.sampled_from(["flip", "truncate", "extend", "set"]))
        if op == "flip" and frame:
            i = draw(st.integers(0, len(frame) - 1))
            frame[i] ^= 1 << draw(st.integers(0, 7))
        elif op == "truncate":
            del frame[draw(st.integers(0, len(frame))):]
        elif op == "extend":
            frame += draw(st.binary(min_size=1, max_size=40))
        elif frame:
            frame[draw(st.integers(0, min(7, len(frame) - 1)))] = draw(st.integers(0, 255))
    return msg, bytes(frame)


@FUZZ
@given(case=mutated(None))
def test_mutated_plain_frames(case):
    msg, frame = case
    d = check(CODECS["plain"](), frame)
    if d is not None and frame == FrameCodec(registry()).encode(msg):
        assert d.msg == msg


@FUZZ
@given(case=mutated(KEY))
def test_mutated_encrypted_frames(case):
    _msg, frame = case
    check(CODECS["aes128cbc"](), frame)
    check(CODECS["plain"](), frame)


@FUZZ
@given(frames=st.lists(messages, max_size=6), junk=st.binary(max_size=64),
       cuts=st.lists(st.integers(1, 50), min_size=1, max_size=20), junk_at=st.integers(0, 6))
def test_stream_reassembly_with_garbage(frames, junk, cuts, junk_at):
    codec = FrameCodec(registry())
    encoded = [codec.encode(m) for m in frames]
    stream = b"".join(encoded[:junk_at]) + junk + b"".join(encoded[junk_at:])
    r = StreamReassembler(max_payload=4096)
    out, i, k = [], 0, 0
    while i < len(stream):
        n = cuts[k % len(cuts)]
        out += r.feed(stream[i:i + n])
        i, k = i + n, k + 1
    # frames before the junk come out intact, in order; after it anything may happen but
    # every frame produced still decodes (or is counted) without raising
    assert out[:min(junk_at, len(encoded))] == encoded[:junk_at] or junk == b""
    for f in out:
        check(codec, f)
    if not junk:
        assert out == encoded and r.broken is None


@pytest.mark.timeout(60)
def test_sockets_survive_random_datagrams_and_streams(tm):
    import random
    rnd = random.Random(7)
    peer = UdpPeer("127.0.0.1", 9, 0, registry=tm.registry(), key=KEY)
    srv = StreamServer(0, registry=tm.registry(), host="127.0.0.1")
    raw = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    try:
        for i in range(200):
            raw.sendto(rnd.randbytes(rnd.randint(0, 1500)), ("127.0.0.1", peer.recv_port))
            if i % 20 == 19:  # read as we go so the kernel's receive buffer never overflows
                assert peer.receive() == []
        tcp = [socket.create_connection(("127.0.0.1", srv.port)) for _ in range(5)]
        for s in tcp:
            s.sendall(rnd.randbytes(rnd.randint(1, 5000)))
            s.close()
        deadline = time.monotonic() + 3
        while time.monotonic() < deadline and (peer.stats.total < 200 or srv.clients()):
            peer.wait(0.01)
            assert peer.receive() == []
            srv.wait(0.01)
            srv.receive()
            srv.events()
        assert peer.stats.total == 200 and srv.clients() == []
    finally:
        raw.close()
        peer.close()
        srv.close()
