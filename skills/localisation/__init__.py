"""Monte Carlo localisation in the style of AMCL, vectorised with numpy.

- :class:`Localiser`: the service of one robot over a backend (odometry and
  laser), with :class:`PoseEstimate` out (pose, covariance, confidence).
- :class:`ParticleFilter`: the algorithm (omnidirectional motion model,
  likelihood-field laser model, KLD sampling, augmented-MCL recovery,
  filterpy's systematic resampling).
- :class:`AmclConfig`: settings with ``standard``, ``cheap`` and ``fixed``
  presets.
"""
from .config import AmclConfig
from .kld import bin_keys, kld_count, kld_prefix_length
from .localiser import Localiser, PoseEstimate, beam_endpoints, select_beams
from .motion import OmniMotionModel, odometry_step
from .particles import ClusterEstimate, ParticleFilter
from .resample import draw, systematic_indices
from .sensor import LikelihoodField

__all__ = ["AmclConfig", "Localiser", "PoseEstimate", "ParticleFilter", "ClusterEstimate",
           "OmniMotionModel", "LikelihoodField", "kld_count", "bin_keys", "kld_prefix_length",
           "odometry_step", "select_beams", "beam_endpoints", "systematic_indices", "draw"]
