"""Encryption exactly as refbox-protocol §1: keys by hand from hashlib, frames by direct AES."""
from __future__ import annotations

import struct

import pytest

from rll_bt.comm import FrameCodec, FrameCrypto, cipher_id, derive_key
from rll_bt.comm import stats as S
from tests.support.comm import aes, hand_key, pkcs7

KEY = "randomkey"


CIPHER_TABLE = [(1, 16, False), (2, 16, True), (3, 32, False), (4, 32, True)]


def test_key_derivation_is_sha256_applied_eight_times():
    assert derive_key(KEY, 2) == hand_key(KEY, 16) == derive_key(KEY, 1)
    assert derive_key(KEY, 4) == hand_key(KEY, 32) == derive_key(KEY, 3)
    # a fixed value too, so a change in both code paths is caught
    golden = "16cf20322cb9067a2b072bfe210e6fb903eef057189c24928520ec857c3e0a09"
    assert derive_key(b"randomkey", "aes-256-cbc").hex() == golden
    assert derive_key("randomkey", "aes-128-cbc").hex() == golden[:32]
    assert len({derive_key(k, 2) for k in ("a", "b", "randomkey")}) == 3


def test_cipher_ids_and_names():
    assert [cipher_id(n) for n in ("aes-128-ecb", "aes-128-cbc", "aes-256-ecb",
                                   "aes-256-cbc")] == [1, 2, 3, 4]
    for bad in (0, 5, "des"):
        with pytest.raises(ValueError):
            cipher_id(bad)


@pytest.mark.parametrize("cipher,keylen,cbc", CIPHER_TABLE)
def test_frame_built_by_direct_aes_decodes(tm, cipher, keylen, cbc):
    body = tm.Hello(name="Carologistics", value=3).SerializeToString()
    plain = struct.pack(">HH", 2000, 1) + body
    iv = bytes(range(16)) if cbc else b""
    payload = iv + aes(hand_key(KEY, keylen), iv or None, pkcs7(plain))
    frame = struct.pack(">BBHI", 2, cipher, 0, len(payload)) + payload
    codec = FrameCodec(tm.registry(), key=KEY)  # sends with 2, accepts any cipher id
    d = codec.decode(frame)
    assert d is not None, codec.stats.as_dict()
    assert d.msg.name == "Carologistics" and d.cipher == cipher


@pytest.mark.parametrize("cipher,keylen,cbc", CIPHER_TABLE)
def test_encoded_frame_decrypts_by_direct_aes(tm, cipher, keylen, cbc):
    msg = tm.Other(x=5, tags=["t" * 20])
    frame = FrameCodec(tm.registry(), key=KEY, cipher=cipher).encode(msg)
    version, cid, reserved, size = struct.unpack(">BBHI", frame[:8])
    assert (version, cid, reserved) == (2, cipher, 0)
    n = 4 + msg.ByteSize()
    ct_len = (n // 16 + 1) * 16
    iv_len = 16 if cbc else 0
    assert len(frame) == 8 + iv_len + ct_len
    assert size == iv_len + ct_len  # peer.cpp's start_send: len(IV) + len(ciphertext)
    iv = frame[8:8 + iv_len]
    plain = aes(hand_key(KEY, keylen), iv or None, frame[8 + iv_len:], decrypt=True)
    assert plain == pkcs7(struct.pack(">HH", 2000, 2) + msg.SerializeToString())


def test_team_cipher_is_aes_128_cbc_with_fresh_iv_per_frame(tm):
    codec = FrameCodec(tm.registry(), key=KEY)
    a, b = codec.encode(tm.Hello(name="x")), codec.encode(tm.Hello(name="x"))
    assert a[1] == 2 and b[1] == 2
    assert a[8:24] != b[8:24] and a[24:] != b[24:]


def test_encrypted_payload_size_is_ignored_on_receipt(tm):
    codec = FrameCodec(tm.registry(), key=KEY)
    frame = bytearray(codec.encode(tm.Hello(name="x")))
    frame[4:8] = struct.pack(">I", len(frame) - 8 - 16)  # header comment's reading: no IV
    assert codec.decode(bytes(frame)).msg.name == "x"


def test_plain_rejected_when_encrypted_and_the_reverse(tm):
    plain = FrameCodec(tm.registry())
    enc = FrameCodec(tm.registry(), key=KEY)
    msg = tm.Hello(name="x")
    assert enc.decode(plain.encode(msg)) is None
    assert plain.decode(enc.encode(msg)) is None
    assert enc.stats.as_dict() == {S.PLAIN_ON_ENCRYPTED: 1}
    assert plain.stats.as_dict() == {S.ENCRYPTED_ON_PLAIN: 1}


def test_wrong_key_is_dropped(tm):
    good = FrameCodec(tm.registry(), key=KEY)
    bad = FrameCodec(tm.registry(), key="otherkey")
    frames = [bad.encode(tm.Hello(name=f"n{i}")) for i in range(50)]
    assert all(good.decode(f) is None for f in frames)
    assert good.stats.total == 50
    # almost all fail the padding check; the rest cannot carry a registered header
    assert good.stats.count(S.DECRYPT_FAILURE) >= 40


def test_crypto_can_be_switched_on_later(tm):
    codec = FrameCodec(tm.registry())
    sender = FrameCodec(tm.registry(), key=KEY)
    f = sender.encode(tm.Hello(name="late"))
    assert codec.decode(f) is None
    codec.set_crypto(KEY)
    assert codec.decode(f).msg.name == "late" and codec.encrypted
    codec.clear_crypto()
    assert codec.decode(f) is None


def test_bad_ciphertext_lengths_fail_cleanly():
    c = FrameCrypto(KEY)
    for data in (b"", bytes(16), bytes(31), bytes(40)):
        with pytest.raises(Exception) as ei:
            c.decrypt(2, data)
        assert "CryptoError" in type(ei.value).__name__
    with pytest.raises(ValueError):
        FrameCrypto("")
