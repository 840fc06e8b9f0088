"""The known map of the field: outer walls and confirmed obstacles.

All coordinates are in the field frame of the rules profile (metres).  At
the start of a game the map holds only the walls; stations are added with
:meth:`FieldMap.add_obstacle` / :meth:`FieldMap.add_station` as they are
confirmed, and every change bumps :attr:`FieldMap.version` so the grids
built from it (localisation's likelihood field, the planner's costmap) know
to rebuild.
"""
from __future__ import annotations

import math

import numpy as np

from rll_bt.backend import Pose2D
from rll_bt.rules import MPS, MpsGeometry, Profile

from .grid import DistanceGrid, GridSpec


def station_footprint(pose: Pose2D, mps: MpsGeometry = MPS, margin: float = 0.0) -> np.ndarray:
    """Corners (4, 2) of a station's base in the field frame; the machine
    frame convention of :mod:`rll_bt.rules.geometry` (x along the conveyor,
    ``depth`` along x, ``width`` along y)."""
    hx, hy = mps.depth / 2.0 + margin, mps.width / 2.0 + margin
    local = np.array([[hx, hy], [-hx, hy], [-hx, -hy], [hx, -hy]])
    c, s = math.cos(pose.theta), math.sin(pose.theta)
    rot = np.array([[c, -s], [s, c]])
    return local @ rot.T + np.array([pose.x, pose.y])


def points_in_polygon(x: np.ndarray, y: np.ndarray, polygon: np.ndarray) -> np.ndarray:
    """Even-odd test of many points against one polygon (k, 2)."""
    inside = np.zeros(np.shape(x), dtype=bool)
    k = len(polygon)
    for a in range(k):
        xi, yi = polygon[a]
        xj, yj = polygon[(a + 1) % k]
        if yi == yj:
            continue
        cross = (yi > y) != (yj > y)
        x_at = xi + (xj - xi) * (y - yi) / (yj - yi)
        inside ^= cross & (x < x_at)
    return inside


def segment_distance(spec: GridSpec, segments: np.ndarray, occupied: np.ndarray,
                     chunk: int = 4096) -> np.ndarray:
    """Exact distance from every cell centre to the nearest segment (0 in
    occupied cells); unlike a distance transform of the raster it has no
    half-cell bias where a wall runs along a cell border."""
    xs, ys = spec.centres()
    px, py = xs.ravel(), ys.ravel()
    a, ab = segments[:, :2], segments[:, 2:] - segments[:, :2]
    len2 = np.maximum((ab * ab).sum(axis=1), 1e-12)
    out = np.empty(len(px))
    for i in range(0, len(px), chunk):
        qx = px[i:i + chunk, None] - a[None, :, 0]
        qy = py[i:i + chunk, None] - a[None, :, 1]
        t = np.clip((qx * ab[None, :, 0] + qy * ab[None, :, 1]) / len2[None, :], 0.0, 1.0)
        dx, dy = qx - t * ab[None, :, 0], qy - t * ab[None, :, 1]
        out[i:i + chunk] = np.sqrt((dx * dx + dy * dy).min(axis=1))
    d = out.reshape(spec.shape)
    d[occupied] = 0.0
    return d


def polygon_edges(polygon: np.ndarray) -> np.ndarray:
    return np.concatenate([polygon, np.roll(polygon, -1, axis=0)], axis=1)


class FieldMap:
    """Walls and obstacles.

    ``boundary`` is the closed outline (k, 2) of the area robots may use
    (field plus insertion areas); its edges are walls.  ``walls`` adds more
    segments (S, 4) as x0, y0, x1, y1.  ``margin`` is the border kept around
    the boundary in the grids.
    """

    def __init__(self, boundary, walls=(), margin: float = 0.5):
        self.boundary = np.asarray(boundary, dtype=float).reshape(-1, 2)
        if len(self.boundary) < 3:
            raise ValueError("the field boundary needs at least three corners")
        extra = np.asarray(walls, dtype=float).reshape(-1, 4)
        self._walls = np.concatenate([polygon_edges(self.boundary), extra], axis=0)
        self._obstacles: dict[str, np.ndarray] = {}
        self.margin = margin
        self.version = 0
        self._grids: dict[float, tuple[int, GridSpec, np.ndarray]] = {}
        self._dist: dict[float, tuple[int, DistanceGrid]] = {}
        self._arena: dict[float, np.ndarray] = {}

    # -- construction -----------------------------------------------------
    @classmethod
    def from_profile(cls, profile: Profile, margin: float = 0.5) -> FieldMap:
        """The profile's field rectangle joined with its insertion areas,
        walled all round (the field's walls and the insertion areas' walls)."""
        f = profile.field
        outline = [(f.x_min, f.y_min)]
        # insertion areas hang below y_min (2016) or lie inside the field (2025);
        # only the ones outside the rectangle change the outline
        outside = sorted((r for r in profile.insertion.values() if r.y_max <= f.y_min + 1e-9),
                         key=lambda r: r.x_min)
        for r in outside:
            outline += [(r.x_min, f.y_min), (r.x_min, r.y_min), (r.x_max, r.y_min), (r.x_max, f.y_min)]
        outline += [(f.x_max, f.y_min), (f.x_max, f.y_max), (f.x_min, f.y_max)]
        pts = [p for i, p in enumerate(outline) if i == 0 or p != outline[i - 1]]
        return cls(np.array(pts), margin=margin)

    # -- obstacles --------------------------------------------------------
    def add_obstacle(self, polygon, name: str | None = None) -> str:
        """Add (or replace, by ``name``) a polygon obstacle; returns its name."""
        poly = np.asarray(polygon, dtype=float).reshape(-1, 2)
        if len(poly) < 3:
            raise ValueError("an obstacle polygon needs at least three corners")
        name = name or f"obstacle{len(self._obstacles) + 1}"
        old = self._obstacles.get(name)
        if old is not None and old.shape == poly.shape and np.allclose(old, poly):
            return name
        self._obstacles[name] = poly
        self.version += 1
        return name

    def add_station(self, name: str, pose: Pose2D, mps: MpsGeometry = MPS) -> str:
        """Add a station's footprint under its machine name ("C-BS")."""
        return self.add_obstacle(station_footprint(pose, mps), name)

    def remove_obstacle(self, name: str) -> None:
        if self._obstacles.pop(name, None) is not None:
            self.version += 1

    @property
    def obstacles(self) -> dict[str, np.ndarray]:
        return dict(self._obstacles)

    def segments(self) -> np.ndarray:
        """All walls and obstacle edges (S, 4)."""
        return np.concatenate([self._walls, self.obstacle_segments()], axis=0)

    def wall_segments(self) -> np.ndarray:
        """The walls (S, 4): the boundary's edges and the extra walls."""
        return self._walls

    def obstacle_segments(self) -> np.ndarray:
        """The obstacles' edges (S, 4); (0, 4) without obstacles."""
        parts = [polygon_edges(p) for p in self._obstacles.values()]
        return np.concatenate(parts, axis=0) if parts else np.zeros((0, 4))

    def clearance(self, x, y, exclude=()) -> np.ndarray:
        """Exact distance (m) from field points to the nearest wall or
        obstacle, leaving out the obstacles named in ``exclude`` (0 inside an
        obstacle or outside the boundary).  For a few points: it checks every
        segment, no grid."""
        px = np.atleast_1d(np.asarray(x, dtype=float))
        py = np.atleast_1d(np.asarray(y, dtype=float))
        polys = [p for n, p in self._obstacles.items() if n not in set(exclude)]
        segs = np.concatenate([self._walls] + [polygon_edges(p) for p in polys], axis=0)
        a, ab = segs[:, :2], segs[:, 2:] - segs[:, :2]
        len2 = np.maximum((ab * ab).sum(axis=1), 1e-12)
        qx, qy = px[:, None] - a[None, :, 0], py[:, None] - a[None, :, 1]
        t = np.clip((qx * ab[None, :, 0] + qy * ab[None, :, 1]) / len2[None, :], 0.0, 1.0)
        d = np.sqrt(((qx - t * ab[None, :, 0]) ** 2 + (qy - t * ab[None, :, 1]) ** 2).min(axis=1))
        blocked = ~self.in_arena(px, py)
        for poly in polys:
            blocked |= points_in_polygon(px, py, poly)
        return np.where(blocked, 0.0, d)

    # -- geometry ---------------------------------------------------------
    @property
    def bounds(self) -> tuple[float, float, float, float]:
        lo = self.boundary.min(axis=0) - self.margin
        hi = self.boundary.max(axis=0) + self.margin
        return float(lo[0]), float(lo[1]), float(hi[0]), float(hi[1])

    def in_arena(self, x, y) -> np.ndarray:
        """Whether points lie inside the boundary (obstacles not considered)."""
        return points_in_polygon(np.asarray(x, float), np.asarray(y, float), self.boundary)

    # -- grids ------------------------------------------------------------
    def grid_spec(self, resolution: float) -> GridSpec:
        return GridSpec.covering(*self.bounds, resolution)

    def occupancy(self, resolution: float) -> tuple[GridSpec, np.ndarray]:
        """(spec, occupied) with walls and obstacles drawn in; cached per
        resolution until the map changes."""
        cached = self._grids.get(resolution)
        if cached is not None and cached[0] == self.version:
            return cached[1], cached[2]
        spec = self.grid_spec(resolution)
        occ = np.zeros(spec.shape, dtype=bool)
        self._draw_segments(spec, occ, self._walls)
        if self._obstacles:
            xs, ys = spec.centres()
            for poly in self._obstacles.values():
                lo, hi = poly.min(axis=0), poly.max(axis=0)
                r0, c0 = spec.cell_of(lo[0], lo[1])
                r1, c1 = spec.cell_of(hi[0], hi[1])
                r0, c0 = max(int(r0), 0), max(int(c0), 0)
                r1, c1 = min(int(r1) + 1, spec.rows), min(int(c1) + 1, spec.cols)
                sub = points_in_polygon(xs[r0:r1, c0:c1], ys[r0:r1, c0:c1], poly)
                occ[r0:r1, c0:c1] |= sub
                self._draw_segments(spec, occ, polygon_edges(poly))
        self._grids[resolution] = (self.version, spec, occ)
        return spec, occ

    def distance(self, resolution: float) -> DistanceGrid:
        """Distance to the nearest wall or obstacle, per cell (cached)."""
        cached = self._dist.get(resolution)
        if cached is not None and cached[0] == self.version:
            return cached[1]
        spec, occ = self.occupancy(resolution)
        dist = DistanceGrid(spec, occ, outside=0.0,
                            distance=segment_distance(spec, self.segments(), occ))
        self._dist[resolution] = (self.version, dist)
        return dist

    def arena_mask(self, resolution: float) -> np.ndarray:
        """Cells whose centre lies inside the boundary."""
        mask = self._arena.get(resolution)
        if mask is None:
            spec = self.grid_spec(resolution)
            mask = self.in_arena(*spec.centres())
            self._arena[resolution] = mask
        return mask

    @staticmethod
    def _draw_segments(spec: GridSpec, occ: np.ndarray, segments: np.ndarray) -> None:
        step = spec.resolution * 0.25
        for x0, y0, x1, y1 in segments:
            n = max(int(math.hypot(x1 - x0, y1 - y0) / step) + 1, 2)
            t = np.linspace(0.0, 1.0, n)
            row, col = spec.cell_of(x0 + (x1 - x0) * t, y0 + (y1 - y0) * t)
            ok = spec.inside(row, col)
            occ[row[ok], col[ok]] = True
