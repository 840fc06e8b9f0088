"""Byte-level fault injection for the emulator's serial links.

``corrupt`` and ``drop`` are per-byte probabilities (0..1), ``delay_ms``
holds every outgoing byte back that long, ``close_every`` (s) closes the
port periodically for ``closed_for`` (s).  Events are drawn with geometric
gaps from a seeded RNG, so a seed reproduces the same fault pattern for the
same byte stream and the cost does not grow with the traffic.
"""
from __future__ import annotations

import math
import random
from dataclasses import dataclass


@dataclass(frozen=True)
class Faults:
    corrupt: float = 0.0
    drop: float = 0.0
    delay_ms: float = 0.0
    close_every: float = 0.0
    closed_for: float = 0.5
    seed: int | None = None

    def __post_init__(self):
        for name in ("corrupt", "drop"):
            p = getattr(self, name)
            if not 0.0 <= p < 1.0:
                raise ValueError(f"{name} probability must be in [0, 1), got {p}")
        for name in ("delay_ms", "close_every", "closed_for"):
            if getattr(self, name) < 0:
                raise ValueError(f"{name} must be >= 0, got {getattr(self, name)}")

    @property
    def any(self) -> bool:
        return bool(self.corrupt or self.drop or self.delay_ms or self.close_every)


class _Gaps:
    """Positions of events with probability ``p`` per byte."""

    def __init__(self, p: float, rng: random.Random):
        self.p, self.rng = p, rng
        self.left = self._draw()

    def _draw(self) -> float:
        if self.p <= 0:
            return math.inf
        u = 1.0 - self.rng.random()
        return math.floor(math.log(u) / math.log1p(-self.p))

    def hits(self, n: int) -> list[int]:
        """Indices in ``range(n)`` where an event happens."""
        out = []
        pos = 0
        while pos + self.left < n:
            pos += int(self.left)
            out.append(pos)
            pos += 1
            self.left = self._draw()
        self.left -= n - pos
        return out


class FaultStream:
    """Applies corruption and drops to one direction of a link."""

    def __init__(self, faults: Faults, rng: random.Random):
        self.rng = rng
        self._corrupt = _Gaps(faults.corrupt, rng)
        self._drop = _Gaps(faults.drop, rng)
        self.corrupted = 0
        self.dropped = 0

    def apply(self, data: bytes) -> bytes:
        if not data:
            return data
        corrupt = self._corrupt.hits(len(data))
        drop = set(self._drop.hits(len(data)))
        if not corrupt and not drop:
            return data
        buf = bytearray(data)
        for i in corrupt:
            buf[i] ^= self.rng.randrange(1, 256)
        self.corrupted += len(corrupt)
        self.dropped += len(drop)
        return bytes(b for i, b in enumerate(buf) if i not in drop)
