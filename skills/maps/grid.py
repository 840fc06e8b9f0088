"""Regular grids over the field and the distance field of an occupancy grid.

A :class:`GridSpec` maps field coordinates (metres) to cells: cell (row i,
column j) covers x in [x0 + j*res, x0 + (j+1)*res) and y in
[y0 + i*res, y0 + (i+1)*res).  Arrays are indexed ``[row, column]`` =
``[y, x]``.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy import ndimage


@dataclass(frozen=True)
class GridSpec:
    x0: float
    y0: float
    resolution: float
    rows: int
    cols: int

    @classmethod
    def covering(cls, x_min: float, y_min: float, x_max: float, y_max: float,
                 resolution: float) -> GridSpec:
        cols = int(np.ceil((x_max - x_min) / resolution))
        rows = int(np.ceil((y_max - y_min) / resolution))
        return cls(float(x_min), float(y_min), float(resolution), rows, cols)

    @property
    def shape(self) -> tuple[int, int]:
        return (self.rows, self.cols)

    def cell_of(self, x, y) -> tuple[np.ndarray, np.ndarray]:
        """(row, col) integer indices, unclipped (may be outside the grid)."""
        col = np.floor((np.asarray(x) - self.x0) / self.resolution).astype(np.int64)
        row = np.floor((np.asarray(y) - self.y0) / self.resolution).astype(np.int64)
        return row, col

    def inside(self, row, col) -> np.ndarray:
        return (row >= 0) & (row < self.rows) & (col >= 0) & (col < self.cols)

    def centre_of(self, row, col) -> tuple[np.ndarray, np.ndarray]:
        """Field coordinates of cell centres."""
        return (self.x0 + (np.asarray(col) + 0.5) * self.resolution,
                self.y0 + (np.asarray(row) + 0.5) * self.resolution)

    def centres(self) -> tuple[np.ndarray, np.ndarray]:
        """Field x and y of every cell centre, each of shape ``shape``."""
        cols, rows = np.meshgrid(np.arange(self.cols), np.arange(self.rows))
        return self.centre_of(rows, cols)


class DistanceGrid:
    """Distance (metres) from each cell to the nearest occupied cell (or a
    given exact ``distance`` array), with a vectorised lookup that returns
    ``outside`` for points off the grid."""

    def __init__(self, spec: GridSpec, occupied: np.ndarray, outside: float = 0.0,
                 distance: np.ndarray | None = None):
        if occupied.shape != spec.shape:
            raise ValueError(f"occupancy shape {occupied.shape} does not match grid {spec.shape}")
        self.spec = spec
        self.occupied = occupied.astype(bool)
        if distance is not None:
            dist = distance
        elif self.occupied.any():
            dist = ndimage.distance_transform_edt(~self.occupied) * spec.resolution
        else:
            dist = np.full(spec.shape, np.inf)
        self.distance = dist.astype(np.float32)
        self.outside = outside

    def lookup(self, x, y) -> np.ndarray:
        row, col = self.spec.cell_of(x, y)
        ok = self.spec.inside(row, col)
        out = np.full(np.shape(row), self.outside, dtype=np.float32)
        out[ok] = self.distance[row[ok], col[ok]]
        return out
