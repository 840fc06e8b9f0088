"""The pieces of the particle filter: motion model, KLD count, resampling,
likelihood field."""
import math

import numpy as np
import pytest

from rll_bt import rules
from rll_bt.backend import Pose2D
from skills.localisation import (
    AmclConfig,
    LikelihoodField,
    OmniMotionModel,
    ParticleFilter,
    bin_keys,
    draw,
    kld_count,
    kld_prefix_length,
    odometry_step,
    systematic_indices,
)
from skills.maps import FieldMap


def test_odometry_step_is_expressed_in_the_first_robot_frame():
    du, dv, dw = odometry_step(Pose2D(1.0, 1.0, math.pi / 2), Pose2D(1.0, 2.0, math.pi))
    assert (du, dv, dw) == pytest.approx((1.0, 0.0, math.pi / 2))


def test_motion_model_moves_by_the_step_with_the_configured_noise():
    model = OmniMotionModel(alpha1=0.1, alpha2=0.05, alpha3=0.2, alpha4=0.05, alpha5=0.1)
    rng = np.random.default_rng(1)
    p = np.tile([0.0, 0.0, math.pi / 2], (20000, 1))
    model.sample(p, (0.4, 0.0, 0.1), rng)        # forward in the robot frame = +y in the field
    s_t, s_s, s_w = model.stddevs(0.4, 0.0, 0.1)
    assert p[:, 1].mean() == pytest.approx(0.4, abs=0.01)
    assert p[:, 0].mean() == pytest.approx(0.0, abs=0.01)
    assert p[:, 1].std() == pytest.approx(s_t, rel=0.05)        # along the motion
    assert p[:, 0].std() == pytest.approx(s_s, rel=0.05)        # strafe
    assert p[:, 2].std() == pytest.approx(s_w, rel=0.05)
    assert s_t == pytest.approx(math.sqrt(0.2 * 0.16 + 0.05 * 0.01))


def test_motion_model_without_motion_adds_no_noise():
    p = np.array([[1.0, 2.0, 0.3]] * 5)
    OmniMotionModel().sample(p, (0.0, 0.0, 0.0), np.random.default_rng(0))
    assert np.allclose(p, [[1.0, 2.0, 0.3]] * 5)


def test_kld_count_grows_with_the_occupied_bins():
    assert kld_count(1) == 1
    n = kld_count(np.arange(2, 200))
    assert np.all(np.diff(n) > 0)
    # (k-1)/(2 eps) * (1 - 2/(9(k-1)) + sqrt(2/(9(k-1))) z)^3 for k = 10
    a = 2.0 / 81.0
    assert kld_count(10, 0.05, 2.326) == pytest.approx(9 / 0.1 * (1 - a + math.sqrt(a) * 2.326) ** 3)


def test_kld_keeps_few_particles_for_a_tight_cloud_and_many_for_a_spread_one():
    rng = np.random.default_rng(3)
    # centred in one 0.5 m x 0.5 m x 10 degree bin
    tight = np.column_stack([rng.normal(2.25, 0.02, 3000), rng.normal(3.25, 0.02, 3000),
                             rng.normal(math.radians(5), 0.01, 3000)])
    straddling = tight - [0.25, 0.25, math.radians(5)]       # the same cloud across 8 bins
    wide = np.column_stack([rng.uniform(-6, 6, 3000), rng.uniform(0, 6, 3000), rng.uniform(-3, 3, 3000)])
    assert kld_prefix_length(bin_keys(tight), 50, 3000, 0.05, 2.326) == 50       # the minimum
    n8 = kld_prefix_length(bin_keys(straddling), 50, 3000, 0.05, 2.326)
    assert n8 == pytest.approx(kld_count(8), abs=1.0)
    assert kld_prefix_length(bin_keys(wide), 50, 3000, 0.05, 2.326) == 3000      # the maximum


def test_resampling_is_deterministic_and_leaves_the_global_rng_alone():
    w = np.random.default_rng(0).random(300)
    w /= w.sum()
    np.random.seed(123)
    state = np.random.get_state()[1].copy()
    a = systematic_indices(w, np.random.default_rng(7))
    b = systematic_indices(w, np.random.default_rng(7))
    assert np.array_equal(a, b)
    assert np.array_equal(np.random.get_state()[1], state)
    counts = np.bincount(draw(w, 30000, np.random.default_rng(1)), minlength=300)
    assert np.abs(counts / 30000 - w).max() < 2.0 / 100     # systematic: within one sample per pass


def test_likelihood_is_highest_at_the_true_pose():
    fmap = FieldMap.from_profile(rules.profile())
    lf = LikelihoodField(fmap, sigma_hit=0.05)
    # a robot at (0, 3) facing +x sees the far walls: +x 6 m, +y 3 m, -y 3 m
    # plus one at 45 degrees, which a turn moves off the wall
    beams = np.array([[6.0, 0.0], [0.0, 3.0], [0.0, -3.0], [3.0, 3.0]])
    poses = np.array([[0.0, 3.0, 0.0], [0.1, 3.0, 0.0], [0.0, 3.2, 0.0], [0.0, 3.0, 0.1]])
    total = lf.log_likelihood(poses, beams).sum(axis=1)
    assert int(np.argmax(total)) == 0
    assert np.all(total[1:] < total[0] - 1.0)


def test_filter_is_reproducible_for_a_seed():
    fmap = FieldMap.from_profile(rules.profile())
    beams = np.array([[6.0, 0.0], [0.0, 3.0], [0.0, -3.0]])
    runs = []
    for _ in range(2):
        pf = ParticleFilter(fmap, AmclConfig.standard(), seed=5)
        pf.initialise(Pose2D(0.2, 3.1, 0.05), (0.2, 0.2, 0.1))
        for _ in range(3):
            pf.predict((0.05, 0.0, 0.0))
            pf.correct(beams)
            pf.resample()
        runs.append(pf.particles.copy())
    assert np.array_equal(runs[0], runs[1])


def test_random_poses_avoid_obstacles_and_stay_in_the_field():
    fmap = FieldMap.from_profile(rules.profile())
    fmap.add_station("X", Pose2D(0.0, 3.0, 0.0))
    pf = ParticleFilter(fmap, AmclConfig.standard(), seed=1)
    p = pf.random_poses(5000)
    assert fmap.in_arena(p[:, 0], p[:, 1]).all()
    clearance = fmap.distance(0.05).lookup(p[:, 0], p[:, 1])
    assert clearance.min() >= 0.225 - 0.04


def test_presets_and_bad_settings():
    assert AmclConfig.cheap().beams < AmclConfig.standard().beams
    assert AmclConfig.fixed(300).min_particles == AmclConfig.fixed(300).max_particles == 300
    with pytest.raises(ValueError, match="unknown localisation preset"):
        AmclConfig.preset("fast")
    with pytest.raises(ValueError):
        AmclConfig(min_particles=10, max_particles=5)
