"""protobuf_comm's frame encryption: AES-128/256 in ECB or CBC with PKCS#7.

Cipher ids as they appear in byte 1 of the frame header (refbox-protocol §1):
0 none, 1 AES-128-ECB, 2 AES-128-CBC, 3 AES-256-ECB, 4 AES-256-CBC.  The refbox
uses 2 on the team channels.

Key derivation follows OpenSSL's ``EVP_BytesToKey(cipher, sha256, salt=NULL,
data=key, count=8)``: ``d = sha256(key)`` then ``d = sha256(d)`` seven more
times; AES-128 takes the first 16 bytes of ``d``, AES-256 all 32.  An
encrypted payload is ``IV (16 B, CBC only) + AES(PKCS7(plaintext))`` with a
fresh random IV for every frame.
"""
from __future__ import annotations

import hashlib
import os
from collections.abc import Callable
from dataclasses import dataclass

from cryptography.hazmat.primitives import padding
from cryptography.hazmat.primitives.ciphers import Cipher, algorithms, modes

from .errors import CryptoError

NONE, AES_128_ECB, AES_128_CBC, AES_256_ECB, AES_256_CBC = 0, 1, 2, 3, 4

#: the cipher the refbox uses on team channels ("aes-128-cbc")
TEAM_CIPHER = AES_128_CBC

BLOCK = 16


@dataclass(frozen=True)
class CipherSpec:
    id: int
    name: str          #: OpenSSL name, e.g. "aes-128-cbc"
    key_len: int       #: bytes
    iv_len: int        #: bytes carried in front of the ciphertext (0 for ECB)


CIPHERS: dict[int, CipherSpec] = {
    AES_128_ECB: CipherSpec(AES_128_ECB, "aes-128-ecb", 16, 0),
    AES_128_CBC: CipherSpec(AES_128_CBC, "aes-128-cbc", 16, 16),
    AES_256_ECB: CipherSpec(AES_256_ECB, "aes-256-ecb", 32, 0),
    AES_256_CBC: CipherSpec(AES_256_CBC, "aes-256-cbc", 32, 16),
}
_BY_NAME = {spec.name: spec.id for spec in CIPHERS.values()}


def cipher_id(cipher: int | str) -> int:
    """Cipher id from an id or an OpenSSL name ("aes-128-cbc"); ValueError otherwise."""
    if isinstance(cipher, str):
        try:
            return _BY_NAME[cipher.lower()]
        except KeyError:
            raise ValueError(f"unknown cipher {cipher!r}; known: {', '.join(sorted(_BY_NAME))}") from None
    if cipher not in CIPHERS:
        raise ValueError(f"unknown cipher id {cipher!r}; known: 1..4 (0 is no encryption)")
    return int(cipher)


def derive_key(key: str | bytes, cipher: int = TEAM_CIPHER) -> bytes:
    """The AES key the refbox derives from a team key string for ``cipher``."""
    spec = CIPHERS[cipher_id(cipher)]
    d = key.encode("utf-8") if isinstance(key, str) else bytes(key)
    d = hashlib.sha256(d).digest()
    for _ in range(7):
        d = hashlib.sha256(d).digest()
    return d[:spec.key_len]


def _mode(spec: CipherSpec, iv: bytes):
    return modes.CBC(iv) if spec.iv_len else modes.ECB()


class FrameCrypto:
    """Encrypts and decrypts frame payloads with one team key.

    Sending uses ``cipher``; receiving accepts any cipher id 1..4 found in a
    frame header, as protobuf_comm's decryptor does, with keys derived from
    the same key string.  ``iv_source`` returns 16 fresh bytes per call
    (default ``os.urandom``).
    """

    def __init__(self, key: str | bytes, cipher: int | str = TEAM_CIPHER,
                 iv_source: Callable[[int], bytes] = os.urandom):
        if key is None or len(key) == 0:
            raise ValueError("an empty crypto key is not allowed")
        self.cipher = cipher_id(cipher)
        self._key_material = key
        self._keys: dict[int, bytes] = {}
        self._iv_source = iv_source

    def key_for(self, cipher: int) -> bytes:
        k = self._keys.get(cipher)
        if k is None:
            k = self._keys[cipher] = derive_key(self._key_material, cipher)
        return k

    def encrypt(self, plaintext: bytes) -> bytes:
        """``IV + ciphertext`` of ``plaintext`` with this object's cipher."""
        spec = CIPHERS[self.cipher]
        iv = self._iv_source(spec.iv_len) if spec.iv_len else b""
        if len(iv) != spec.iv_len:
            raise ValueError(f"iv_source returned {len(iv)} bytes, need {spec.iv_len}")
        padder = padding.PKCS7(BLOCK * 8).padder()
        padded = padder.update(plaintext) + padder.finalize()
        enc = Cipher(algorithms.AES(self.key_for(self.cipher)), _mode(spec, iv)).encryptor()
        return iv + enc.update(padded) + enc.finalize()

    def decrypt(self, cipher: int, data: bytes) -> bytes:
        """Plaintext of ``IV + ciphertext`` under ``cipher``; :class:`CryptoError` if it fails."""
        spec = CIPHERS.get(cipher)
        if spec is None:
            raise CryptoError(f"unknown cipher id {cipher}")
        body = data[spec.iv_len:]
        if len(data) < spec.iv_len + BLOCK or len(body) % BLOCK:
            raise CryptoError(f"{len(data)} bytes is not a valid {spec.name} payload")
        iv = bytes(data[:spec.iv_len])
        dec = Cipher(algorithms.AES(self.key_for(cipher)), _mode(spec, iv)).decryptor()
        padded = dec.update(bytes(body)) + dec.finalize()
        unpadder = padding.PKCS7(BLOCK * 8).unpadder()
        try:
            return unpadder.update(padded) + unpadder.finalize()
        except ValueError:
            raise CryptoError("bad PKCS#7 padding (wrong key?)") from None
