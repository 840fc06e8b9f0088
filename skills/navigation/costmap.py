"""The planner's costmap: the known map inflated by the robot's radius,
plus laser obstacles that expire.

A cell is *lethal* when the robot centred there would come closer than
``robot_radius + padding`` to a wall or station, closer than
``robot_radius + padding + obstacle_padding`` to a recent laser obstacle
(another robot: the laser check keeps a wider berth from those, and a path
it would not let the robot drive is no path), or lies outside the field
boundary.  Other cells cost 1 plus a penalty that
falls off linearly over ``inflation`` metres of extra clearance, so paths
keep away from stations when there is room.
"""
from __future__ import annotations

import numpy as np
from scipy import ndimage

from ..maps import FieldMap, GridSpec


class Costmap:
    def __init__(self, field_map: FieldMap, resolution: float = 0.05, robot_radius: float = 0.225,
                 padding: float = 0.05, inflation: float = 0.35, penalty: float = 4.0,
                 obstacle_padding: float = 0.08):
        self.map = field_map
        self.resolution = resolution
        self.robot_radius = robot_radius
        self.padding = padding
        self.inflation = inflation
        self.penalty = penalty
        self.obstacle_padding = obstacle_padding
        self.spec: GridSpec = field_map.grid_spec(resolution)
        self._temp_points = np.zeros((0, 2))
        self._temp_expiry = np.zeros(0)
        self.version = 0                       # bumps on any change (map or obstacles)
        self._map_version = -1
        self._temp_dirty = True
        self._static_clearance: np.ndarray | None = None
        self._arena = field_map.arena_mask(resolution)
        self._built: tuple[np.ndarray, np.ndarray] | None = None

    @property
    def lethal_radius(self) -> float:
        return self.robot_radius + self.padding

    # -- laser obstacles --------------------------------------------------
    def add_obstacles(self, points: np.ndarray, now: float, ttl: float) -> None:
        """Mark field points (K, 2) as obstacles until ``now + ttl``."""
        pts = np.asarray(points, dtype=float).reshape(-1, 2)
        if len(pts) == 0:
            return
        self._temp_points = np.concatenate([self._temp_points, pts])
        self._temp_expiry = np.concatenate([self._temp_expiry, np.full(len(pts), now + ttl)])
        self._temp_dirty = True

    def expire(self, now: float) -> None:
        keep = self._temp_expiry > now
        if not keep.all():
            self._temp_points, self._temp_expiry = self._temp_points[keep], self._temp_expiry[keep]
            self._temp_dirty = True

    def clear_obstacles(self) -> None:
        if len(self._temp_points):
            self._temp_points, self._temp_expiry = np.zeros((0, 2)), np.zeros(0)
            self._temp_dirty = True

    @property
    def temporary_obstacles(self) -> np.ndarray:
        return self._temp_points.copy()

    # -- grids ------------------------------------------------------------
    def grids(self) -> tuple[np.ndarray, np.ndarray]:
        """(lethal bool grid, cost float grid), rebuilt only on change."""
        if self.map.version != self._map_version:
            self._static_clearance = self.map.distance(self.resolution).distance.astype(np.float64)
            self._map_version = self.map.version
            self._temp_dirty = True
        if self._temp_dirty or self._built is None:
            clearance = self._static_clearance
            if len(self._temp_points):
                occ = np.zeros(self.spec.shape, dtype=bool)
                row, col = self.spec.cell_of(self._temp_points[:, 0], self._temp_points[:, 1])
                ok = self.spec.inside(row, col)
                occ[row[ok], col[ok]] = True
                if occ.any():
                    temp = ndimage.distance_transform_edt(~occ) * self.resolution
                    clearance = np.minimum(clearance, np.maximum(temp - self.obstacle_padding, 0.0))
            lethal = (clearance < self.lethal_radius) | ~self._arena
            extra = np.clip(1.0 - (clearance - self.lethal_radius) / self.inflation, 0.0, 1.0)
            cost = 1.0 + self.penalty * extra
            self._built = (lethal, cost)
            self._clearance = clearance
            self._temp_dirty = False
            self.version += 1
        return self._built

    def clearance(self) -> np.ndarray:
        self.grids()
        return self._clearance

    def clearance_at(self, x, y) -> np.ndarray:
        """Clearance (m) at field points, interpolated bilinearly between cell
        centres (a cell's own value holds only at its centre; 0 off the grid)."""
        clear = self.clearance()
        spec = self.spec
        fx = (np.asarray(x, dtype=float) - spec.x0) / spec.resolution - 0.5
        fy = (np.asarray(y, dtype=float) - spec.y0) / spec.resolution - 0.5
        c0, r0 = np.floor(fx).astype(np.int64), np.floor(fy).astype(np.int64)
        tx, ty = fx - c0, fy - r0
        inside = (r0 >= 0) & (r0 + 1 < spec.rows) & (c0 >= 0) & (c0 + 1 < spec.cols)
        r0, c0 = np.clip(r0, 0, spec.rows - 2), np.clip(c0, 0, spec.cols - 2)
        v = (clear[r0, c0] * (1 - tx) * (1 - ty) + clear[r0, c0 + 1] * tx * (1 - ty)
             + clear[r0 + 1, c0] * (1 - tx) * ty + clear[r0 + 1, c0 + 1] * tx * ty)
        return np.where(inside, v, 0.0)

    def segment_clearance(self, x0: float, y0: float, x1: float, y1: float) -> float:
        """The least clearance (m) along a straight segment (interpolated,
        sampled every quarter cell)."""
        n = max(int(np.hypot(x1 - x0, y1 - y0) / (self.resolution * 0.25)) + 1, 2)
        t = np.linspace(0.0, 1.0, n)
        return float(self.clearance_at(x0 + (x1 - x0) * t, y0 + (y1 - y0) * t).min())

    def is_free(self, x, y) -> np.ndarray:
        """Whether the robot may stand at the points (not lethal, on the grid)."""
        lethal, _ = self.grids()
        row, col = self.spec.cell_of(x, y)
        ok = self.spec.inside(row, col)
        out = np.zeros(np.shape(row), dtype=bool)
        out[ok] = ~lethal[row[ok], col[ok]]
        return out

    def segment_free(self, x0: float, y0: float, x1: float, y1: float) -> bool:
        """Whether every point of the straight segment is free (sampled at
        half the resolution)."""
        n = max(int(np.hypot(x1 - x0, y1 - y0) / (self.resolution * 0.5)) + 1, 2)
        t = np.linspace(0.0, 1.0, n)
        return bool(self.is_free(x0 + (x1 - x0) * t, y0 + (y1 - y0) * t).all())

    def nearest_free(self, x: float, y: float, max_distance: float = 0.6) -> tuple[float, float] | None:
        """The free cell centre nearest to (x, y) within ``max_distance``."""
        lethal, _ = self.grids()
        row, col = self.spec.cell_of(x, y)
        k = int(np.ceil(max_distance / self.resolution))
        r0, r1 = max(int(row) - k, 0), min(int(row) + k + 1, self.spec.rows)
        c0, c1 = max(int(col) - k, 0), min(int(col) + k + 1, self.spec.cols)
        if r0 >= r1 or c0 >= c1:
            return None
        sub = ~lethal[r0:r1, c0:c1]
        rr, cc = np.nonzero(sub)
        if len(rr) == 0:
            return None
        xs, ys = self.spec.centre_of(rr + r0, cc + c0)
        d = np.hypot(xs - x, ys - y)
        i = int(np.argmin(d))
        if d[i] > max_distance:
            return None
        return float(xs[i]), float(ys[i])
