"""Omnidirectional odometry motion model, sampled for many particles at once.

An odometry step is the robot's displacement (du, dv, dw) between two
odometry poses, expressed in the robot frame at the first of them (du
forward, dv left, dw counter-clockwise; metres and radians).  Each particle
moves by the same step plus noise whose variance grows with the step, in
the manner of AMCL's ``alpha1..alpha5`` (variance multipliers):

- rotation error:    var = alpha1 * dw^2 + alpha2 * t^2
- translation error along the direction of motion:  var = alpha3 * t^2 + alpha4 * dw^2
- strafe error across the direction of motion:      var = alpha5 * t^2 + alpha4 * dw^2

with t = hypot(du, dv).  For a pure rotation the translation errors lie
along the robot's x and y axes.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from rll_bt.backend import Pose2D


def odometry_step(before: Pose2D, after: Pose2D) -> tuple[float, float, float]:
    """(du, dv, dw) of ``after`` in the frame of ``before``."""
    rel = after.relative_to(before)
    return rel.x, rel.y, rel.theta


@dataclass(frozen=True)
class OmniMotionModel:
    alpha1: float = 0.1
    alpha2: float = 0.05
    alpha3: float = 0.1
    alpha4: float = 0.05
    alpha5: float = 0.1

    def stddevs(self, du: float, dv: float, dw: float) -> tuple[float, float, float]:
        """(translation, strafe, rotation) standard deviations for a step."""
        t2, w2 = du * du + dv * dv, dw * dw
        return (math.sqrt(self.alpha3 * t2 + self.alpha4 * w2),
                math.sqrt(self.alpha5 * t2 + self.alpha4 * w2),
                math.sqrt(self.alpha1 * w2 + self.alpha2 * t2))

    def sample(self, particles: np.ndarray, step: tuple[float, float, float],
               rng: np.random.Generator) -> np.ndarray:
        """Move ``particles`` (N, 3: x, y, theta) in place by ``step`` plus noise."""
        du, dv, dw = step
        n = len(particles)
        s_t, s_s, s_w = self.stddevs(du, dv, dw)
        t = math.hypot(du, dv)
        phi = math.atan2(dv, du) if t > 1e-9 else 0.0
        cp, sp = math.cos(phi), math.sin(phi)
        noise = rng.standard_normal((n, 3))
        e_t, e_s = noise[:, 0] * s_t, noise[:, 1] * s_s
        u = du + cp * e_t - sp * e_s
        v = dv + sp * e_t + cp * e_s
        w = dw + noise[:, 2] * s_w
        th = particles[:, 2]
        c, s = np.cos(th), np.sin(th)
        particles[:, 0] += c * u - s * v
        particles[:, 1] += s * u + c * v
        particles[:, 2] = (th + w + np.pi) % (2.0 * np.pi) - np.pi
        return particles
