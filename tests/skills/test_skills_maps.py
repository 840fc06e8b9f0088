"""The known map: outline from the profile, stations, grids and ray casting."""
import math

import numpy as np
import pytest

from rll_bt import rules
from rll_bt.backend import Pose2D
from skills.maps import FieldMap, cast_rays, march_rays, station_footprint


def test_2016_outline_includes_the_insertion_areas():
    m = FieldMap.from_profile(rules.profile("rcll2016"))
    assert m.in_arena(np.array([4.5, -4.5, 0.0, 0.0]), np.array([-0.5, -0.5, -0.5, 3.0])).tolist() == \
        [True, True, False, True]
    assert not m.in_arena(np.array([6.1]), np.array([3.0]))[0]


def test_2025_outline_is_the_field_rectangle():
    m = FieldMap.from_profile(rules.profile("rcll2025"))
    assert m.boundary.min(axis=0).tolist() == [-7.0, 0.0] and m.boundary.max(axis=0).tolist() == [7.0, 8.0]


def test_station_footprint_follows_the_machine_frame():
    fp = station_footprint(Pose2D(1.0, 2.0, math.pi / 2))
    # depth 0.35 along the machine x (field y here), width 0.7 across
    assert fp[:, 0].max() - fp[:, 0].min() == pytest.approx(0.70)
    assert fp[:, 1].max() - fp[:, 1].min() == pytest.approx(0.35)


def test_adding_a_station_changes_the_grids():
    m = FieldMap.from_profile(rules.profile())
    before = m.distance(0.05).lookup(np.array([1.0]), np.array([3.0]))[0]
    v = m.version
    m.add_station("C-CS1", Pose2D(1.0, 3.0, 0.0))
    assert m.version == v + 1
    assert m.distance(0.05).lookup(np.array([1.0]), np.array([3.0]))[0] == 0.0
    assert before == pytest.approx(3.0, abs=0.04)        # nearest wall: y = 6 or y = 0
    m.add_station("C-CS1", Pose2D(1.0, 3.0, 0.0))        # the same again: no change
    assert m.version == v + 1
    m.remove_obstacle("C-CS1")
    assert m.distance(0.05).lookup(np.array([1.0]), np.array([3.0]))[0] == pytest.approx(before)


def test_distance_grid_is_exact_to_within_half_a_cell():
    m = FieldMap.from_profile(rules.profile())
    d = m.distance(0.05)
    xs = np.array([5.5, 5.9, 0.0, -5.8])
    ys = np.array([3.0, 3.0, 5.7, 0.3])
    truth = np.array([0.5, 0.1, 0.3, 0.2])
    assert np.abs(d.lookup(xs, ys) - truth).max() <= 0.036


def test_ray_casting_against_segments_and_the_grid():
    m = FieldMap.from_profile(rules.profile())
    m.add_station("X", Pose2D(2.0, 3.0, 0.0))
    angles = np.array([0.0, math.pi / 2, math.pi, -math.pi / 2])
    exact = cast_rays(np.array([0.0, 3.0]), angles, m.segments(), 20.0)
    assert exact.tolist() == pytest.approx([2.0 - 0.175, 3.0, 6.0, 3.0])
    spec, occ = m.occupancy(0.05)
    marched = march_rays(spec, occ, (0.0, 3.0), angles, 20.0)
    assert np.abs(marched - exact).max() < 0.06
    assert math.isinf(cast_rays(np.array([0.0, 3.0]), np.array([0.0]), m.segments(), 1.0)[0])
