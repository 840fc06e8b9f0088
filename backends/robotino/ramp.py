"""Host-side velocity ramping of the Robotino base (the firmware ramps only
motor rpm; the host limits body accelerations, as Fawkes does).
Units: m/s, rad/s, m/s^2, rad/s^2, seconds."""
from __future__ import annotations

import math
from dataclasses import dataclass


@dataclass(frozen=True)
class RampLimits:
    """Host-side velocity ramp (Fawkes defaults): m/s^2 and rad/s^2."""
    trans_accel: float = 0.8
    trans_decel: float = 1.5
    rot_accel: float = 1.6
    rot_decel: float = 3.14


def _ramp_axis(current: float, target: float, accel: float, decel: float, dt: float) -> float:
    if current == target:
        return target
    speeding_up = abs(target) > abs(current) and (current == 0 or (current > 0) == (target > 0))
    step = (accel if speeding_up else decel) * dt
    if abs(target - current) <= step:
        return target
    return current + math.copysign(step, target - current)


def ramp(current: tuple[float, float, float], target: tuple[float, float, float],
         dt: float, limits: RampLimits = RampLimits()) -> tuple[float, float, float]:
    """One ramp step of ``dt`` seconds from ``current`` towards ``target``
    (vx, vy, omega), per axis: accelerating while the speed grows in the same
    direction, decelerating otherwise."""
    return (_ramp_axis(current[0], target[0], limits.trans_accel, limits.trans_decel, dt),
            _ramp_axis(current[1], target[1], limits.trans_accel, limits.trans_decel, dt),
            _ramp_axis(current[2], target[2], limits.rot_accel, limits.rot_decel, dt))
