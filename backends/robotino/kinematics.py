"""Omni-drive kinematics of the Robotino 3 and odometry from wheel speeds.

Robot frame: x forward, y left, angles counter-clockwise.  Motor speeds are
motor rpm before the gearbox, motors 0, 1, 2 (m1, m2, m3 in Festo's sample
code).  With ``k = 60 * gear / (2 * pi * rw)`` (rpm per m/s at the rim)::

    m1 = k * (-(sqrt3/2) vx + vy/2 + rb w)
    m2 = k * (-vy + rb w)
    m3 = k * ( (sqrt3/2) vx + vy/2 + rb w)

and the inverse ``vx = (m3 - m1) / (sqrt3 k)``,
``vy = 2/3 (m1 + (m3 - m1)/2 - m2) / k``, ``w = (vy + m2/k) / rb``.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

SQRT3 = math.sqrt(3.0)


def round_half_away(x: float) -> int:
    """C's ``roundf``: halves round away from zero."""
    return int(math.floor(x + 0.5)) if x >= 0 else -int(math.floor(-x + 0.5))


@dataclass(frozen=True)
class OmniKinematics:
    """Three-wheel omni drive.  ``rb`` centre to wheel (m), ``rw`` wheel radius
    (m), ``gear`` reduction, ``rpm_max`` the motor set-point limit."""
    rb: float = 0.175
    rw: float = 0.060
    gear: float = 32.0
    rpm_max: float = 3000.0

    @property
    def k(self) -> float:
        """Motor rpm per m/s at the wheel rim."""
        return 60.0 * self.gear / (2.0 * math.pi * self.rw)

    def forward(self, vx: float, vy: float, omega: float) -> tuple[float, float, float]:
        """Body velocity (m/s, m/s, rad/s) -> motor rpm of motors 0, 1, 2."""
        k, r = self.k, self.rb * omega
        return (k * (-SQRT3 / 2.0 * vx + 0.5 * vy + r),
                k * (-vy + r),
                k * (SQRT3 / 2.0 * vx + 0.5 * vy + r))

    def inverse(self, m1: float, m2: float, m3: float) -> tuple[float, float, float]:
        """Motor rpm of motors 0, 1, 2 -> body velocity (m/s, m/s, rad/s)."""
        k = self.k
        vx = (m3 - m1) / (SQRT3 * k)
        vy = 2.0 / 3.0 * (m1 + 0.5 * (m3 - m1) - m2) / k
        omega = (vy + m2 / k) / self.rb
        return vx, vy, omega

    def clamped(self, vx: float, vy: float, omega: float) -> tuple[float, float, float]:
        """The command within the motors' reach: when a motor would turn
        faster than ``rpm_max``, the whole command is scaled down until it
        turns at ``rpm_max``.  The robot then drives the path it was told to
        (the same direction and curve), only slower; Fawkes clamps each wheel
        alone, which bends the path (a robot 0.2 m from a station face drove
        into it)."""
        top = max(abs(m) for m in self.forward(vx, vy, omega))
        if top <= self.rpm_max:
            return vx, vy, omega
        scale = self.rpm_max / top
        return vx * scale, vy * scale, omega * scale

    def setpoints(self, vx: float, vy: float, omega: float) -> tuple[int, int, int]:
        """Integer motor set-points as sent to the base: the command
        :meth:`clamped` to the motors' reach, then rounded half away from zero
        (as Fawkes rounds)."""
        lim = self.rpm_max
        return tuple(round_half_away(max(-lim, min(lim, m)))  # type: ignore[return-value]
                     for m in self.forward(*self.clamped(vx, vy, omega)))


class OdometryIntegrator:
    """Dead reckoning from measured motor speeds, as Fawkes integrates it:
    ``phi += w dt; x += (cos phi vx - sin phi vy) dt; y += (sin phi vx + cos phi vy) dt``
    (the heading is updated first).  Pose in m and rad in the odometry frame,
    velocities in m/s and rad/s in the robot frame."""

    def __init__(self, kinematics: OmniKinematics | None = None):
        self.kinematics = kinematics or OmniKinematics()
        self.reset()

    def reset(self, x: float = 0.0, y: float = 0.0, phi: float = 0.0) -> None:
        self.x, self.y, self.phi = float(x), float(y), float(phi)
        self.vx = self.vy = self.omega = 0.0

    def update(self, rpm: tuple[float, float, float], dt: float) -> tuple[float, float, float]:
        """Integrate ``dt`` seconds at motor speeds ``rpm``; returns the pose."""
        self.vx, self.vy, self.omega = self.kinematics.inverse(*rpm)
        if dt > 0:
            self.phi += self.omega * dt
            c, s = math.cos(self.phi), math.sin(self.phi)
            self.x += (c * self.vx - s * self.vy) * dt
            self.y += (s * self.vx + c * self.vy) * dt
        return self.x, self.y, self.phi
