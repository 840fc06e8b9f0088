"""Costmap and global planner."""
import math

import numpy as np
import pytest

from rll_bt import rules
from rll_bt.backend import Pose2D
from skills.maps import FieldMap
from skills.navigation import Costmap, GridPlanner, NoPath, shortcut


@pytest.fixture
def field():
    m = FieldMap.from_profile(rules.profile())
    m.add_station("A", Pose2D(0.0, 3.0, math.pi / 2))      # 0.7 m wide along x, 0.35 along y
    return m


def path_clearance(path, fmap, step=0.02):
    d = fmap.distance(0.05)
    pts = []
    for a, b in zip(path[:-1], path[1:]):
        n = max(int(np.hypot(*(b - a)) / step), 1)
        t = np.linspace(0, 1, n + 1)[:, None]
        pts.append(a + (b - a) * t)
    pts = np.vstack(pts)
    return float(d.lookup(pts[:, 0], pts[:, 1]).min())


def test_path_goes_around_a_station_with_clearance(field):
    cm = Costmap(field)
    path = GridPlanner(cm).plan((0.0, 1.5), (0.0, 4.5))
    assert path[0].tolist() == [0.0, 1.5] and path[-1].tolist() == [0.0, 4.5]
    assert path_clearance(path, field) >= cm.lethal_radius - 0.04
    length = np.hypot(*np.diff(path, axis=0).T).sum()
    assert 3.0 < length < 4.5                    # around, not through, and not a huge detour


def test_smoothing_leaves_few_waypoints_on_open_ground(field):
    path = GridPlanner(Costmap(field)).plan((-5.0, 1.0), (5.0, 1.0))
    assert len(path) == 2


def test_no_path_into_a_closed_pocket(field):
    cm = Costmap(field)
    # wall the right end off with laser obstacles across the field
    ys = np.arange(-1.0, 6.0, 0.05)             # field and insertion area
    cm.add_obstacles(np.column_stack([np.full_like(ys, 4.0), ys]), now=0.0, ttl=5.0)
    with pytest.raises(NoPath):
        GridPlanner(cm).plan((0.0, 1.0), (5.0, 1.0))
    cm.expire(10.0)                               # the obstacles are gone again
    assert len(GridPlanner(cm).plan((0.0, 1.0), (5.0, 1.0))) >= 2


def test_start_and_goal_next_to_a_station_are_snapped_free(field):
    cm = Costmap(field)
    start = (0.0, 3.0 - 0.175 - 0.25)             # docked: too close to the face for the costmap
    assert not cm.is_free(*start)
    path = GridPlanner(cm).plan(start, (3.0, 3.0))
    assert tuple(path[0]) == start and cm.is_free(*path[1])
    with pytest.raises(NoPath, match="blocked"):
        GridPlanner(cm, snap_distance=0.2).plan((0.0, 1.0), (0.0, 3.0))   # inside the station


def test_costmap_prefers_distance_from_obstacles(field):
    cm = Costmap(field)
    lethal, cost = cm.grids()
    near = cm.spec.cell_of(0.0, 3.0 - 0.175 - 0.3)
    far = cm.spec.cell_of(0.0, 3.0 - 0.175 - 1.0)
    assert cost[near] > cost[far] == 1.0
    assert lethal[cm.spec.cell_of(0.0, 3.0 - 0.175 - 0.2)]


def test_shortcut_keeps_a_two_point_path():
    cm = Costmap(FieldMap.from_profile(rules.profile()))
    p = np.array([[0.0, 1.0], [1.0, 1.0]])
    assert np.array_equal(shortcut(p, cm), p)
