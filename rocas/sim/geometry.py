"""Vectorised planar geometry: angles, oriented boxes, polylines, polygons, rays."""

from __future__ import annotations

import numpy as np

from rocas import numerics


def clip(x: np.ndarray, lo: np.ndarray | float, hi: np.ndarray | float) -> np.ndarray:
    """``np.clip`` without its Python-level overhead (hot loops call it thousands of times)."""
    return np.minimum(np.maximum(x, lo), hi)


_TWO_PI = 2.0 * np.pi
_WRAP_CHECK_SIZE = 64  # from this size on, testing the range first is cheaper than ``%``


def wrap_angle(a: np.ndarray | float) -> np.ndarray:
    """Angles wrapped to [-pi, pi)."""
    y = np.asarray(a) + np.pi
    # ``y % 2pi`` is y itself for y in [0, 2pi) (and y is never -0.0 here); numpy's float
    # remainder costs about 15 ns an element, two range reductions far less on large arrays
    if (y.size >= _WRAP_CHECK_SIZE and np.minimum.reduce(y, axis=None) >= 0.0
            and np.maximum.reduce(y, axis=None) < _TWO_PI):
        return y - np.pi
    return y % _TWO_PI - np.pi


def box_gap(
    ax: np.ndarray, ay: np.ndarray, ayaw: np.ndarray, ahl: np.ndarray, ahw: np.ndarray,
    bx: np.ndarray, by: np.ndarray, byaw: np.ndarray, bhl: np.ndarray, bhw: np.ndarray,
) -> np.ndarray:
    """Separating-axis gap between oriented boxes (broadcasting shapes).

    Returns the largest separation over the four box axes [m]: negative when the boxes
    overlap (penetration depth), positive otherwise (a lower bound of the true distance).
    """
    dx = bx - ax
    dy = by - ay
    ca, sa = np.cos(ayaw), np.sin(ayaw)
    cb, sb = np.cos(byaw), np.sin(byaw)
    # relative orientation terms
    cab = np.abs(ca * cb + sa * sb)  # |cos(a-b)|
    sab = np.abs(sa * cb - ca * sb)  # |sin(a-b)|
    g1 = np.abs(dx * ca + dy * sa) - (ahl + bhl * cab + bhw * sab)
    g2 = np.abs(-dx * sa + dy * ca) - (ahw + bhl * sab + bhw * cab)
    g3 = np.abs(dx * cb + dy * sb) - (bhl + ahl * cab + ahw * sab)
    g4 = np.abs(-dx * sb + dy * cb) - (bhw + ahl * sab + ahw * cab)
    return np.maximum(np.maximum(g1, g2), np.maximum(g3, g4))


def box_corners(x: np.ndarray, y: np.ndarray, yaw: np.ndarray, hl: np.ndarray, hw: np.ndarray
                ) -> np.ndarray:
    """Corners of oriented boxes, shape ``(..., 4, 2)`` (front-left, front-right, rear-right,
    rear-left)."""
    c, s = np.cos(yaw)[..., None], np.sin(yaw)[..., None]
    lx = np.array([1.0, 1.0, -1.0, -1.0]) * np.asarray(hl)[..., None]
    ly = np.array([1.0, -1.0, -1.0, 1.0]) * np.asarray(hw)[..., None]
    px = np.asarray(x)[..., None] + lx * c - ly * s
    py = np.asarray(y)[..., None] + lx * s + ly * c
    return np.stack([px, py], axis=-1)


def resample_polyline(points: np.ndarray, count: int) -> tuple[np.ndarray, float]:
    """Resample a polyline (P, 2) to ``count`` equally spaced points; returns (points, spacing)."""
    seg = np.hypot(*np.diff(points, axis=0).T)
    s = np.concatenate([[0.0], np.cumsum(seg)])
    total = float(s[-1])
    t = np.linspace(0.0, total, count)
    return np.stack([np.interp(t, s, points[:, 0]), np.interp(t, s, points[:, 1])], -1), (
        total / (count - 1) if count > 1 else 0.0)


def polyline_headings(points: np.ndarray) -> np.ndarray:
    """Tangent heading at each point of (..., P, 2) polylines [rad] (central differences)."""
    d = np.gradient(points, axis=-2)
    return numerics.arctan2(d[..., 1], d[..., 0])


def polyline_curvature(points: np.ndarray, spacing: float) -> np.ndarray:
    """Signed curvature of an equally spaced polyline (P, 2) [1/m]."""
    h = np.unwrap(polyline_headings(points))
    return np.gradient(h) / max(spacing, 1e-9)


def points_in_polygons(px: np.ndarray, py: np.ndarray, edges: np.ndarray, edge_owner: np.ndarray,
                       num_polygons: int) -> np.ndarray:
    """Even-odd point-in-polygon test.

    Args:
        px, py: points, shape (..., K).
        edges: polygon edges (E, 4) as x0, y0, x1, y1.
        edge_owner: polygon index of each edge (E,).
        num_polygons: G.

    Returns:
        bool array (..., K, G).
    """
    x0, y0, x1, y1 = edges[:, 0], edges[:, 1], edges[:, 2], edges[:, 3]
    X = px[..., None]
    Y = py[..., None]
    straddle = (y0 > Y) != (y1 > Y)
    with np.errstate(divide="ignore", invalid="ignore"):
        xc = x0 + (Y - y0) * (x1 - x0) / (y1 - y0)
    cross = straddle & (X < xc)
    onehot = np.zeros((edges.shape[0], num_polygons), dtype=np.int64)
    onehot[np.arange(edges.shape[0]), edge_owner] = 1
    counts = cross.astype(np.int64) @ onehot  # integer matmul: numpy's own loop, never BLAS
    return (counts % 2) == 1


def segments_blocked(ox: np.ndarray, oy: np.ndarray, tx: np.ndarray, ty: np.ndarray,
                     edges: np.ndarray) -> np.ndarray:
    """Whether the segment from (ox, oy) to (tx, ty) crosses each edge.

    Shapes: ``ox, oy`` broadcastable against ``tx, ty`` (..., K); edges (E, 4).
    Returns bool (..., K, E).
    """
    x0, y0, x1, y1 = edges[:, 0], edges[:, 1], edges[:, 2], edges[:, 3]
    rx = (tx - ox)[..., None]
    ry = (ty - oy)[..., None]
    sx = x1 - x0
    sy = y1 - y0
    qpx = x0 - np.asarray(ox)[..., None]
    qpy = y0 - np.asarray(oy)[..., None]
    denom = rx * sy - ry * sx
    with np.errstate(divide="ignore", invalid="ignore"):
        t = (qpx * sy - qpy * sx) / denom
        u = (qpx * ry - qpy * rx) / denom
    return (np.abs(denom) > 1e-12) & (t > 0.0) & (t < 1.0) & (u >= 0.0) & (u <= 1.0)


def segments_blocked_by_edge(ox: np.ndarray, oy: np.ndarray, tx: np.ndarray, ty: np.ndarray,
                             edges: np.ndarray) -> np.ndarray:
    """:func:`segments_blocked` with the edges as the leading axis: bool (E, ...) for segments
    ``(ox, oy) -> (tx, ty)`` of broadcast shape (...). Each element is computed with the very
    same operations; a reduction over the edges then runs over the outer axis (numpy reduces
    a short inner axis about ten times slower)."""
    shape = (edges.shape[0],) + (1,) * np.ndim(tx)
    x0, y0, x1, y1 = (edges[:, j].reshape(shape) for j in range(4))
    rx = tx - ox
    ry = ty - oy
    sx = x1 - x0
    sy = y1 - y0
    qpx = x0 - ox
    qpy = y0 - oy
    denom = rx * sy - ry * sx
    with np.errstate(divide="ignore", invalid="ignore"):
        t = (qpx * sy - qpy * sx) / denom
        u = (qpx * ry - qpy * rx) / denom
    return (np.abs(denom) > 1e-12) & (t > 0.0) & (t < 1.0) & (u >= 0.0) & (u <= 1.0)


def _k_smallest(d2: np.ndarray, k: int) -> np.ndarray:
    """Indices (R, k) of each row's k smallest values, ties broken towards the lower index, in
    ascending index order. (``argpartition`` breaks ties by its SIMD path, so the same world
    would get other candidates on another CPU.)"""
    kth = np.partition(d2, k - 1, axis=1)[:, k - 1:k]  # the k-th smallest value: unique
    below = d2 < kth
    tied = (d2 == kth) & (np.cumsum(d2 == kth, axis=1) <= k - below.sum(axis=1, keepdims=True))
    return np.argsort(~(below | tied), axis=1, kind="stable")[:, :k]


#: NearestGrid.build works on square tiles of this many cells a side
TILE_CELLS = 32


class NearestGrid:
    """Nearest-point queries against a fixed point set (lane samples, a reference line).

    A regular grid stores, per cell, the K points nearest to the cell centre within a radius;
    a query checks only those K candidates. Queries far from every point return the sentinel
    index ``num_points`` (callers pad their arrays with a far-away point there).
    """

    def __init__(self, origin: np.ndarray, cell_m: float, candidates: np.ndarray,
                 points: np.ndarray) -> None:
        self.origin = origin
        self.cell_m = cell_m
        self.candidates = candidates  # (GX, GY, K) int
        self.shape = candidates.shape[:2]
        self._flat = candidates.reshape(-1, candidates.shape[2])  # (GX * GY, K): one gather
        # the point set plus a far-away sentinel row (index num_points)
        self.points = np.vstack([points, [[1e7, 1e7]]])
        # each cell's candidates' coordinates, (GX * GY, K) each: a query gathers a cell's row
        # instead of its indices and then their points
        self._flat_x = np.ascontiguousarray(self.points[self._flat, 0])
        self._flat_y = np.ascontiguousarray(self.points[self._flat, 1])

    @classmethod
    def build(cls, points: np.ndarray, cell_m: float, k: int, margin_m: float) -> NearestGrid:
        """The grid over ``points`` (P, 2) [m] with ``cell_m`` cells reaching ``margin_m``
        past them: each cell keeps the (at most) ``k`` points nearest its centre within
        0.75 ``cell_m`` + ``margin_m`` (ties towards the lower index), in ascending index
        order, then the sentinel ``P`` in the slots left.

        Built tile by tile (TILE_CELLS x TILE_CELLS cells), each tile against only the points
        inside its box grown by that radius (plus a metre, so that rounding cannot leave out
        a point on the edge): a point outside it is farther than the radius from every centre
        of the tile. The squared distances are those of all points against all centres, so the
        candidates are the same. A replayed catalog map's two grids took 0.4-2.2 s this way
        against every point (A12 1.9 s) and take 0.06-0.12 s tile by tile (docs/benchmarks.md)."""
        lo = points.min(axis=0) - margin_m
        hi = points.max(axis=0) + margin_m
        gx, gy = (np.ceil((hi - lo) / cell_m).astype(int) + 1).tolist()
        cx = lo[0] + (np.arange(gx) + 0.5) * cell_m
        cy = lo[1] + (np.arange(gy) + 0.5) * cell_m
        n = points.shape[0]
        cand = np.full((gx, gy, k), n, dtype=np.int64)
        radius = cell_m * 0.75 + margin_m
        reach = radius + 1.0
        px, py = points[:, 0], points[:, 1]
        for i0 in range(0, gx, TILE_CELLS):
            tx = cx[i0:i0 + TILE_CELLS]
            in_x = (px >= tx[0] - reach) & (px <= tx[-1] + reach)
            for j0 in range(0, gy, TILE_CELLS):
                ty = cy[j0:j0 + TILE_CELLS]
                sel = np.flatnonzero(in_x & (py >= ty[0] - reach) & (py <= ty[-1] + reach))
                if sel.size == 0:
                    continue
                c = np.stack(np.meshgrid(tx, ty, indexing="ij"), -1).reshape(-1, 2)
                d2 = ((c[:, None, 0] - px[sel][None, :]) ** 2
                      + (c[:, None, 1] - py[sel][None, :]) ** 2)
                k_eff = min(k, sel.size)
                idx = _k_smallest(d2, k_eff)
                near = np.take_along_axis(d2, idx, 1) <= radius * radius
                # the points within the radius first (still in ascending index order)
                order = np.argsort(~near, axis=1, kind="stable")
                idx = np.take_along_axis(idx, order, 1)
                near = np.take_along_axis(near, order, 1)
                block = np.where(near, sel[idx], n).reshape(len(tx), len(ty), k_eff)
                cand[i0:i0 + len(tx), j0:j0 + len(ty), :k_eff] = block
        return cls(lo, cell_m, cand, points)

    def cell(self, x: np.ndarray, y: np.ndarray) -> np.ndarray:
        """Index of the grid cell of (x, y) into the flattened grid, shape as ``x``."""
        ix = clip(((x - self.origin[0]) / self.cell_m).astype(np.int64), 0, self.shape[0] - 1)
        iy = clip(((y - self.origin[1]) / self.cell_m).astype(np.int64), 0, self.shape[1] - 1)
        return ix * self.shape[1] + iy

    def query(self, x: np.ndarray, y: np.ndarray) -> np.ndarray:
        """Candidate point indices near (x, y), shape (..., K)."""
        return np.take(self._flat, self.cell(x, y), axis=0)


def nearest_on(grid: NearestGrid, x: np.ndarray, y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Index of the grid's nearest point and the squared distance to it, for query points of
    any shape (far queries get the sentinel index ``num_points`` at a huge distance)."""
    cell = grid.cell(x, y)
    # the candidates' coordinates, one row of each table per query (``take`` of rows is
    # several times faster than indexing with an array)
    px = np.take(grid._flat_x, cell, axis=0)  # (..., K)
    py = np.take(grid._flat_y, cell, axis=0)
    d2 = (px - x[..., None]) ** 2 + (py - y[..., None]) ** 2
    # the argmin's entries, gathered from flat rows (what take_along_axis does, without its
    # Python overhead)
    k = px.shape[-1]
    d22 = d2.reshape(-1, k)
    j = d22.argmin(axis=1)
    flat_j = _arange(d22.shape[0]) * k + j
    return (grid._flat.reshape(-1).take(cell.reshape(-1) * k + j).reshape(cell.shape),
            d22.reshape(-1).take(flat_j).reshape(cell.shape))


_ARANGES: dict[int, np.ndarray] = {}


def _arange(n: int) -> np.ndarray:
    """``np.arange(n)``, made once per n (read-only)."""
    out = _ARANGES.get(n)
    if out is None:
        out = np.arange(n)
        out.flags.writeable = False
        _ARANGES[n] = out
    return out
