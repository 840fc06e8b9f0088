"""Whether the gripper holds a workpiece, from one of the base's inputs.

The Carologistics gripper cannot tell by itself; a team may wire a sensor
(an IR distance sensor looking into the jaws, a light barrier on an analog
or digital input).  :class:`HoldingSensor` names that input:

* ``"distance:N>V"`` / ``"distance:N<V"``: IR sensor N (0..8) voltage above
  (below) V volts means holding;
* ``"analog:N>V"`` / ``"analog:N<V"``: analog input N (0..7), volts;
* ``"digital:N"`` (holding when input N is high) or ``"digital:N=0"``
  (holding when it is low), N in 0..7.
"""
from __future__ import annotations

import math
import re
from dataclasses import dataclass

_ANALOG = re.compile(r"^(distance|analog):(\d+)\s*([<>])\s*([-+0-9.eE]+)$")
_DIGITAL = re.compile(r"^digital:(\d+)(?:=([01]))?$")
_COUNT = {"distance": 9, "analog": 8, "digital": 8}


@dataclass(frozen=True)
class HoldingSensor:
    source: str                 # "distance", "analog" or "digital"
    index: int
    threshold: float = 0.0      # volts (distance, analog)
    above: bool = True          # holding when value > threshold (digital: when the bit is 1)

    def __post_init__(self):
        if self.source not in _COUNT:
            raise ValueError(f"holding sensor source must be distance, analog or digital, not {self.source!r}")
        if not 0 <= self.index < _COUNT[self.source]:
            raise ValueError(f"{self.source} input {self.index} does not exist "
                             f"(0..{_COUNT[self.source] - 1})")
        if not math.isfinite(self.threshold):
            raise ValueError(f"holding sensor threshold must be finite, got {self.threshold}")

    @classmethod
    def parse(cls, text: str) -> HoldingSensor:
        spec = text.strip().replace(" ", "")
        m = _ANALOG.match(spec)
        if m:
            try:
                threshold = float(m.group(4))
            except ValueError:
                raise ValueError(f"bad threshold in holding sensor {text!r}") from None
            return cls(m.group(1), int(m.group(2)), threshold, m.group(3) == ">")
        m = _DIGITAL.match(spec)
        if m:
            return cls("digital", int(m.group(1)), 0.0, m.group(2) != "0")
        raise ValueError(f"holding sensor {text!r} is not like 'distance:8>1.5', "
                         "'analog:0<2.0', 'digital:3' or 'digital:3=0'")

    def evaluate(self, readings) -> bool | None:
        """From a :class:`base.BaseReadings`; None before the first reading."""
        if math.isnan(readings.stamp):
            return None
        if self.source == "digital":
            return bool(readings.digital_inputs >> self.index & 1) == self.above
        values = readings.distance_voltages if self.source == "distance" else readings.analog_inputs
        v = values[self.index]
        return v > self.threshold if self.above else v < self.threshold
