"""rocas.sim.geometry: results that do not depend on how many elements a call gets."""

from __future__ import annotations

import numpy as np
import pytest

from rocas.sim.geometry import wrap_angle


def test_wrap_angle_gives_each_element_the_same_bits_in_a_large_or_small_call():
    # large calls skip ``%`` when every angle is already in range; a variant's angle must not
    # depend on the batch it is wrapped in
    rng = np.random.default_rng(3)
    edge = np.array([0.0, -0.0, np.pi, -np.pi, np.nextafter(np.pi, 0), np.nextafter(-np.pi, 0),
                     1e-300, -1e-300])
    in_range = np.concatenate([rng.uniform(-np.pi, np.pi, 500), edge])
    mixed = np.concatenate([in_range, rng.uniform(-40.0, 40.0, 500)])
    for angles in (in_range, mixed):
        one_by_one = np.array([wrap_angle(np.array([a]))[0] for a in angles])
        together = wrap_angle(angles)
        assert np.array_equal(together.view(np.int64), one_by_one.view(np.int64))
        assert np.all((together >= -np.pi) & (together < np.pi))


def _grid_by_brute_force(points, cell_m, k, margin_m):
    """NearestGrid.build's definition, every point against every cell centre: per cell the k
    nearest within the radius (ties towards the lower index), ascending, then sentinels."""
    from rocas.sim.geometry import NearestGrid

    lo = points.min(axis=0) - margin_m
    gx, gy = (np.ceil((points.max(axis=0) + margin_m - lo) / cell_m).astype(int) + 1).tolist()
    cx = lo[0] + (np.arange(gx) + 0.5) * cell_m
    cy = lo[1] + (np.arange(gy) + 0.5) * cell_m
    centers = np.stack(np.meshgrid(cx, cy, indexing="ij"), -1).reshape(-1, 2)
    radius = cell_m * 0.75 + margin_m
    n = len(points)
    rows = []
    for c in centers:
        d2 = (c[0] - points[:, 0]) ** 2 + (c[1] - points[:, 1]) ** 2
        order = sorted(range(n), key=lambda i: (d2[i], i))[:k]
        near = sorted(i for i in order if d2[i] <= radius * radius)
        rows.append(near + [n] * (k - len(near)))
    return NearestGrid(lo, cell_m, np.array(rows, dtype=np.int64).reshape(gx, gy, k), points)


@pytest.mark.parametrize("seed", range(4))
def test_the_tiled_nearest_grid_is_the_grid_of_every_point_against_every_cell(seed):
    """build() compares each tile of cells only with the points near it; the candidates are
    those of comparing every point with every cell (duplicates and equal distances too), and
    so are the nearest points queries find."""
    from rocas.sim.geometry import NearestGrid, nearest_on

    rng = np.random.default_rng(seed)
    pts = np.round(rng.uniform(-60.0, 90.0, size=(int(rng.integers(3, 120)), 2)), 1)
    pts = np.vstack([pts, pts[:2]])  # equal points: ties broken by index
    cell, k, margin = [(1.0, 4, 12.0), (5.0, 24, 10.0), (2.0, 3, 0.0), (1.0, 6, 3.0)][seed]
    got = NearestGrid.build(pts, cell, k, margin)
    want = _grid_by_brute_force(pts, cell, k, margin)
    assert np.array_equal(got.candidates, want.candidates)
    q = rng.uniform(pts.min(0) - 40.0, pts.max(0) + 40.0, size=(5000, 2))
    for a, b in zip(nearest_on(got, q[:, 0], q[:, 1]), nearest_on(want, q[:, 0], q[:, 1]), strict=True):
        assert np.array_equal(a, b)
