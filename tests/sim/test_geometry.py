"""rocas.sim.geometry: results that do not depend on how many elements a call gets."""

from __future__ import annotations

import numpy as np

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
