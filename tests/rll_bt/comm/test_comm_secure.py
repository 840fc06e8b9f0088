"""The secured team-server link: AES-GCM with sequence numbers, fresh keys per connection."""
from __future__ import annotations

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from rll_bt.comm import stats as S
from rll_bt.comm.framing import Drop
from rll_bt.comm.secure import CLIENT, HELLO, SEALED, SERVER, SecureSession, is_secure_frame


def pair(key_s="team key", key_c="team key"):
    srv, cli = SecureSession(key_s, SERVER), SecureSession(key_c, CLIENT)
    assert cli.open(srv.hello()) is None and srv.open(cli.hello()) is None
    assert srv.ready and cli.ready
    return srv, cli


def cause(fn, *args):
    with pytest.raises(Drop) as e:
        fn(*args)
    return e.value.cause


def test_messages_pass_both_ways_in_order():
    srv, cli = pair()
    for i in range(5):
        assert srv.open(cli.seal(b"to server %d" % i)) == b"to server %d" % i
        assert cli.open(srv.seal(b"to robot %d" % i)) == b"to robot %d" % i


def test_frames_are_v2_frames_of_the_link_ciphers():
    srv, cli = pair()
    hello, sealed = cli.hello(), cli.seal(b"x" * 10)
    assert hello[:2] == bytes([2, HELLO]) and sealed[:2] == bytes([2, SEALED])
    assert int.from_bytes(sealed[4:8], "big") == len(sealed) - 8    # a stream can split frames
    assert is_secure_frame(hello) and is_secure_frame(sealed)
    assert not is_secure_frame(bytes([2, 2, 0, 0, 0, 0, 0, 0]))


def test_a_replayed_frame_is_dropped():
    srv, cli = pair()
    f1, f2 = cli.seal(b"one"), cli.seal(b"two")
    assert srv.open(f1) == b"one"
    assert cause(srv.open, f1) == S.REPLAY
    assert srv.open(f2) == b"two"
    assert cause(srv.open, f2) == S.REPLAY


def test_a_frame_from_an_earlier_session_does_not_open():
    srv, cli = pair()
    old = cli.seal(b"move to C-BS")
    assert srv.open(old) == b"move to C-BS"
    srv2, _cli2 = pair()                        # reconnected: new nonces, new keys
    assert cause(srv2.open, old) == S.AUTH_FAILURE


def test_every_altered_byte_is_detected():
    srv, cli = pair()
    frame = cli.seal(b"retrieve C-CS1 output")
    for i in range(len(frame)):
        bad = bytearray(frame)
        bad[i] ^= 0x01
        with pytest.raises(Drop):
            srv.open(bytes(bad))
    assert srv.open(frame) == b"retrieve C-CS1 output"     # the genuine one still opens


def test_a_peer_without_the_key_completes_the_hello_but_nothing_opens():
    srv, intruder = pair(key_c="guessed")
    assert cause(srv.open, intruder.seal(b"drive off the field")) == S.AUTH_FAILURE
    assert cause(intruder.open, srv.seal(b"secret")) == S.AUTH_FAILURE


def test_handshake_errors():
    srv = SecureSession("k", SERVER)
    assert cause(srv.open, SecureSession("k", SERVER).hello()) == S.HANDSHAKE   # same role
    cli = SecureSession("k", CLIENT)
    assert cause(srv.open, cli.hello()[:-1]) == S.SIZE_MISMATCH
    early = SecureSession("k", CLIENT)
    early.open(srv.hello())
    sealed = early.seal(b"x")
    fresh = SecureSession("k", SERVER)
    assert cause(fresh.open, sealed) == S.HANDSHAKE                           # before its hello
    srv.open(cli.hello())
    assert cause(srv.open, cli.hello()) == S.HANDSHAKE                        # twice
    assert cause(srv.open, bytes([2, 0, 0, 0, 0, 0, 0, 4]) + b"\0\0\0\1") == S.PLAIN_ON_ENCRYPTED
    with pytest.raises(RuntimeError):
        SecureSession("k", CLIENT).seal(b"too early")
    with pytest.raises(ValueError):
        SecureSession("", CLIENT)


@settings(max_examples=300, deadline=None)
@given(st.binary(max_size=200))
def test_random_bytes_never_escape_as_anything_but_a_drop(data):
    srv, _cli = pair()
    try:
        out = srv.open(data)
    except Drop as drop:
        assert drop.cause in S.CAUSES
    else:
        pytest.fail(f"random bytes opened to {out!r}")


@settings(max_examples=200, deadline=None)
@given(st.binary(min_size=0, max_size=300), st.integers(0, 400), st.integers(1, 255))
def test_mutated_sealed_frames_are_dropped(message, where, xor):
    srv, cli = pair()
    frame = bytearray(cli.seal(message))
    frame[where % len(frame)] ^= xor
    with pytest.raises(Drop):
        srv.open(bytes(frame))
