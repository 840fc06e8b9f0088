"""Settings of the Monte Carlo localiser, with named presets.

- :meth:`AmclConfig.standard`: 500 particles to start, 100..1000 by KLD,
  60 beams, updates after 0.1 m or 0.1 rad of motion; the benchmarked
  accuracy setting.
- :meth:`AmclConfig.cheap`: for whole simulated games with three robots in
  one process: 60..300 particles, 24 beams, updates after 0.2 m or 0.2 rad,
  no updates while standing still once confident.
- :meth:`AmclConfig.fixed`: a constant particle count (KLD off), for timing.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

from .motion import OmniMotionModel

#: the presets a running robot may be given (``rll-bt agent --localisation``;
#: ``fixed`` is for timing only)
PRESETS = ("cheap", "standard")


@dataclass(frozen=True)
class AmclConfig:
    # particle count: start, then KLD-adapted within [min, max]
    particles: int = 500
    min_particles: int = 100
    max_particles: int = 1000
    kld_epsilon: float = 0.05
    kld_z: float = 2.326                 # upper 0.99 quantile of the standard normal
    kld_bin_xy: float = 0.25             # metres
    kld_bin_theta: float = math.radians(10.0)
    # laser
    beams: int = 60
    sigma_hit: float = 0.08              # metres
    z_hit: float = 0.9
    z_rand: float = 0.1
    grid_resolution: float = 0.05        # metres per likelihood-field cell
    # Beams are not independent: the summed log-likelihood is divided by this
    # many beams' worth (weights as if from ``beams / beam_correlation`` beams).
    beam_correlation: float = 4.0
    # motion
    motion: OmniMotionModel = field(default_factory=OmniMotionModel)
    update_min_d: float = 0.1            # metres of travel before a filter update
    update_min_a: float = 0.1            # radians of turn before a filter update
    still_update_period: float | None = 0.5   # s; update a standing robot while not confident
    still_jitter: tuple[float, float] = (0.01, 0.01)   # m, rad of roughening for those
    resample_interval: int = 1
    # recovery (augmented MCL); alpha_slow 0 disables injection
    alpha_slow: float = 0.001
    alpha_fast: float = 0.1
    recovery_ratio: float = 0.7          # inject once w_fast falls below this share of w_slow
    max_injection: float = 0.15          # at most this share of random particles per resample
    trim_beams: float = 0.0              # share of worst beams left out of the recovery statistic
    inject_above_contradiction: float = 0.05   # inject only while more beams than this pass mapped walls
    lost_injection: float = 0.2          # share of random particles per resample while lost (all particles kept)
    # confidence
    confident: float = 0.6               # above this the pose is trusted
    lost: float = 0.2                    # below this for lost_updates updates: lost
    unsure_side: float = 0.25            # reported confidence at most this until a tag confirms a global search
    lost_updates: int = 5
    fit_tolerance: float = 0.15          # metres, a beam agrees with the map within this
    station_slack: float = 0.5           # metres a beam may reach past a mapped station face (its pose may be off)
    # a scan that pins the position in one direction only (a long wall and nothing else mapped in
    # range): along the other the pose follows the odometry (observability.py); below this many
    # beams' worth of evidence along the weakest direction (0: never)
    hold_below: float = 1.0
    cluster_xy: float = 0.3              # metres, particles within this of the best bin
    cluster_theta: float = math.radians(20.0)

    def __post_init__(self):
        if not 1 <= self.min_particles <= self.max_particles:
            raise ValueError("need 1 <= min_particles <= max_particles")
        if self.beams < 1:
            raise ValueError("need at least one beam")

    @classmethod
    def standard(cls, **changes) -> AmclConfig:
        return replace(cls(), **changes)

    @classmethod
    def cheap(cls, **changes) -> AmclConfig:
        return replace(cls(particles=200, min_particles=60, max_particles=300, beams=24,
                           update_min_d=0.2, update_min_a=0.2, still_update_period=1.0,
                           beam_correlation=2.0), **changes)

    @classmethod
    def fixed(cls, particles: int = 500, beams: int = 60, **changes) -> AmclConfig:
        return replace(cls(particles=particles, min_particles=particles, max_particles=particles,
                           beams=beams), **changes)

    @classmethod
    def preset(cls, name: str, **changes) -> AmclConfig:
        presets = {"standard": cls.standard, "cheap": cls.cheap, "fixed": cls.fixed}
        try:
            return presets[name](**changes)
        except KeyError:
            raise ValueError(f"unknown localisation preset {name!r} "
                             f"(known: {', '.join(presets)})") from None
