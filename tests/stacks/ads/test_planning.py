"""Planning helpers that replace numpy functions must give numpy's bits."""

from __future__ import annotations

import numpy as np

from rocas.stacks.ads.planning import _row_gradient


def test_row_gradient_is_numpys_gradient_bit_for_bit():
    rng = np.random.default_rng(5)
    for k in (2, 3, 41):
        a = np.cumsum(rng.normal(size=(7, k)) * 10.0 ** rng.integers(-8, 4, size=(7, k)), axis=1)
        assert np.array_equal(_row_gradient(a).view(np.int64),
                              np.gradient(a, axis=1).view(np.int64))
