"""Global path planning on the costmap: Dijkstra over the 8-connected grid
(scipy's compiled ``csgraph.dijkstra``), then line-of-sight shortcutting.

The graph is rebuilt only when the costmap changed.  A start or goal in a
lethal cell (the robot standing close to a station after docking, a goal
right at a station) is moved to the nearest free cell within
``snap_distance``; the path then begins/ends with the straight piece to
the true point.
"""
from __future__ import annotations

import math

import numpy as np
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import dijkstra

from .costmap import Costmap

_SQRT2 = math.sqrt(2.0)
# (d_row, d_col, length in cells); the reverse edges come from undirected search
_MOVES = ((0, 1, 1.0), (1, 0, 1.0), (1, 1, _SQRT2), (1, -1, _SQRT2))


class NoPath(Exception):
    pass


class GridPlanner:
    def __init__(self, costmap: Costmap, snap_distance: float = 0.6):
        self.costmap = costmap
        self.snap_distance = snap_distance
        self._graph_version = -1
        self._graph = None

    def _build(self) -> None:
        lethal, cost = self.costmap.grids()
        if self._graph is not None and self._graph_version == self.costmap.version:
            return
        rows, cols = lethal.shape
        idx = np.arange(rows * cols).reshape(rows, cols)
        free = ~lethal
        src, dst, w = [], [], []
        res = self.costmap.resolution
        for dr, dc, length in _MOVES:
            r0, r1 = max(0, -dr), rows - max(0, dr)
            c0, c1 = max(0, -dc), cols - max(0, dc)
            a = (slice(r0, r1), slice(c0, c1))
            b = (slice(r0 + dr, r1 + dr), slice(c0 + dc, c1 + dc))
            ok = free[a] & free[b]
            if dr and dc:     # no corner cutting past a lethal cell
                ok &= free[r0 + dr:r1 + dr, c0:c1] & free[r0:r1, c0 + dc:c1 + dc]
            src.append(idx[a][ok])
            dst.append(idx[b][ok])
            w.append(length * res * 0.5 * (cost[a][ok] + cost[b][ok]))
        src, dst, w = np.concatenate(src), np.concatenate(dst), np.concatenate(w)
        self._graph = coo_matrix((w, (src, dst)), shape=(rows * cols, rows * cols)).tocsr()
        self._graph_version = self.costmap.version

    def _snap(self, x: float, y: float, what: str) -> tuple[int, tuple[float, float]]:
        cm = self.costmap
        if bool(cm.is_free(x, y)):
            p = (x, y)
        else:
            p = cm.nearest_free(x, y, self.snap_distance)
            if p is None:
                raise NoPath(f"the {what} ({x:.2f}, {y:.2f}) is blocked and no free cell is within "
                             f"{self.snap_distance:.2f} m")
        row, col = cm.spec.cell_of(p[0], p[1])
        return int(row) * cm.spec.cols + int(col), p

    def costs_from(self, start: tuple[float, float], limit: float) -> np.ndarray:
        """The path cost (the costmap's weighted metres) from ``start`` to
        every cell, an array of the costmap's shape: inf where it is more
        than ``limit`` or no path leads; raises :class:`NoPath` when the
        start is blocked."""
        self._build()
        s_node, _ = self._snap(*start, "start")
        dist = dijkstra(self._graph, directed=False, indices=s_node, limit=limit)
        return np.asarray(dist).reshape(self.costmap.spec.shape)

    def plan(self, start: tuple[float, float], goal: tuple[float, float]) -> np.ndarray:
        """Waypoints (K, 2) from ``start`` to ``goal`` (field frame), smoothed;
        raises :class:`NoPath`."""
        self._build()
        s_node, s_pt = self._snap(*start, "start")
        g_node, g_pt = self._snap(*goal, "goal")
        if s_node == g_node:
            return np.array([start, goal], dtype=float)
        dist, pred = dijkstra(self._graph, directed=False, indices=s_node, return_predecessors=True)
        if not np.isfinite(dist[g_node]):
            raise NoPath(f"no path from ({start[0]:.2f}, {start[1]:.2f}) to ({goal[0]:.2f}, {goal[1]:.2f})")
        nodes = [g_node]
        while nodes[-1] != s_node:
            nodes.append(int(pred[nodes[-1]]))
        nodes.reverse()
        cols = self.costmap.spec.cols
        xs, ys = self.costmap.spec.centre_of(np.array(nodes) // cols, np.array(nodes) % cols)
        cells = np.column_stack([xs, ys])
        cells[0], cells[-1] = s_pt, g_pt
        path = shortcut(cells, self.costmap)
        if s_pt != tuple(start):
            path = np.vstack([start, path])
        if g_pt != tuple(goal):
            path = np.vstack([path, goal])
        return path


def shortcut(path: np.ndarray, costmap: Costmap) -> np.ndarray:
    """Greedy line-of-sight smoothing: from each kept point jump to the
    farthest later point reachable by a straight line that stays as clear
    of obstacles as the grid path does (and never inside the lethal
    radius; clearance interpolated between cell centres, so a line cannot
    slip between two free cell centres past a corner).  The far end is
    probed in coarse steps first, then refined, so long paths need few
    checks."""
    if len(path) <= 2:
        return path.copy()
    n = len(path)

    def visible(i: int, k: int) -> bool:
        return _keeps_clearance(path, i, k, costmap)

    out = [path[0]]
    i = 0
    while i < n - 1:
        step = max((n - 1 - i) // 8, 1)
        j = i + 1
        for k in range(n - 1, i + 1, -step):
            if visible(i, k):
                j = k
                break
        while j + 1 < n and visible(i, j + 1):
            j += 1
        out.append(path[j])
        i = j
    return np.array(out)


def _keeps_clearance(path: np.ndarray, i: int, k: int, costmap: Costmap, slack: float = 0.01) -> bool:
    """The straight line i..k stays at least as clear as the grid path's
    tightest point between them (capped at the inflation distance), less
    ``slack`` metres, and outside the lethal radius."""
    seg = path[i:k + 1]
    need = min(float(costmap.clearance_at(seg[:, 0], seg[:, 1]).min()),
               costmap.lethal_radius + costmap.inflation) - slack
    need = max(need, costmap.lethal_radius)
    x0, y0 = path[i]
    x1, y1 = path[k]
    return costmap.segment_clearance(x0, y0, x1, y1) >= need
