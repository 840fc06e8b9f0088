"""From per-frame light states to ON, OFF or BLINK per light.

Production signals blink (about 2 Hz in the 2016 table), so one frame shows
a blinking light either on or off.  The filter keeps a window of recent
frames (time stamped, from one station) and calls a light

- ON when it was on in at least ``on_ratio`` of the window,
- OFF when it was on in at most ``1 - on_ratio`` of it,
- BLINK when, in between, it changed state at least ``min_toggles`` times
  and was seen on and off in at least ``min_phase_frames`` frames each,

and UNKNOWN until that light's readings in the window span ``min_span``
seconds.  Frames without a reading (the tower not found, or read unsure)
are not in the window: the filter holds its call over them.  A reading that
comes with the light network's class probabilities is taken light by light:
a light whose probability of being on (the sum over the states that have it
on) lies between ``1 - light_confidence`` and ``light_confidence`` is left
out of that frame (a lamp half lit by its neighbour's glow, or caught in its
blink's edge), the other lights of the frame count.  A light that is on about half of the
time but never toggled, or that toggled around one odd frame (a detector
flip-flopping on one bad reading), stays UNKNOWN rather than guessed.
"""
from __future__ import annotations

from collections import deque
from dataclasses import dataclass

from rll_bt.backend.types import LIGHT_NAMES

ON, OFF, BLINK, UNKNOWN = "ON", "OFF", "BLINK", "UNKNOWN"


@dataclass(frozen=True)
class LightPattern:
    green: str
    yellow: str
    red: str

    def as_dict(self) -> dict[str, str]:
        return {"green": self.green, "yellow": self.yellow, "red": self.red}

    @property
    def complete(self) -> bool:
        return UNKNOWN not in (self.green, self.yellow, self.red)

    @property
    def steady_state(self) -> int | None:
        """The 0..7 code when no light blinks and all are known, else None."""
        vals = (self.green, self.yellow, self.red)
        if not self.complete or BLINK in vals:
            return None
        return sum(1 << i for i, v in enumerate(vals) if v == ON)


class LightFilter:
    def __init__(self, window: float = 2.0, min_span: float = 1.2, on_ratio: float = 0.85,
                 min_toggles: int = 2, max_frames: int = 200, min_phase_frames: int = 2,
                 light_confidence: float = 0.9):
        self.window, self.min_span = window, min_span
        self.on_ratio, self.min_toggles = on_ratio, min_toggles
        self.min_phase_frames = min_phase_frames
        self.light_confidence = light_confidence
        self._frames: deque[tuple[float, int, int]] = deque(maxlen=max_frames)   # (stamp, state, lights read)

    def add(self, stamp: float, state: int, probabilities=None) -> None:
        """One frame's reading: ``state`` 0..7, with the light network's
        eight class ``probabilities`` when it gave them (see the module doc)."""
        if not 0 <= state <= 7:
            raise ValueError(f"light state must be 0..7, got {state}")
        read = 7
        if probabilities is not None and len(probabilities) == 8:
            for bit in range(3):
                on = sum(p for s, p in enumerate(probabilities) if s >> bit & 1)
                if 1.0 - self.light_confidence < on < self.light_confidence:
                    read &= ~(1 << bit)
        if self._frames and stamp < self._frames[-1][0]:
            self._frames.clear()                      # time went backwards: start again
        self._frames.append((stamp, state, read))
        while self._frames and stamp - self._frames[0][0] > self.window:
            self._frames.popleft()

    def reset(self) -> None:
        self._frames.clear()

    def pattern(self) -> LightPattern:
        out = []
        for bit in range(3):
            frames = [(t, s) for t, s, read in self._frames if read >> bit & 1]
            if len(frames) < 3 or frames[-1][0] - frames[0][0] < self.min_span:
                out.append(UNKNOWN)
                continue
            seq = [(s >> bit) & 1 for _, s in frames]
            ratio = sum(seq) / len(seq)
            toggles = sum(1 for a, b in zip(seq, seq[1:]) if a != b)
            if ratio >= self.on_ratio:
                out.append(ON)
            elif ratio <= 1.0 - self.on_ratio:
                out.append(OFF)
            elif toggles >= self.min_toggles and min(sum(seq), len(seq) - sum(seq)) >= self.min_phase_frames:
                out.append(BLINK)
            else:
                out.append(UNKNOWN)
        return LightPattern(*out)


__all__ = ["LightFilter", "LightPattern", "ON", "OFF", "BLINK", "UNKNOWN", "LIGHT_NAMES"]
