import math

import numpy as np
import pytest

from rocas.search.objectives import (
    ego_dissimilarity,
    scenario_dissimilarity,
    suspiciousness,
    trajectory_mse,
)


def test_close_and_in_front_is_more_suspicious():
    ego, heading = (0.0, 0.0), 0.0
    front_near = suspiciousness([(5.0, 0.0)], ego, heading)
    front_far = suspiciousness([(50.0, 0.0)], ego, heading)
    behind_near = suspiciousness([(-5.0, 0.0)], ego, heading)
    assert front_near < front_far and front_near < behind_near
    assert front_near == pytest.approx(-(10 / 5 + 1))
    assert suspiciousness([(0.0, 5.0)], ego, math.pi / 2) == pytest.approx(-(10 / 5 + 1))


def test_global_entities_count_without_direction():
    assert suspiciousness([None], (0, 0), 0.0, k=10) == pytest.approx(-10 / 50)


def test_trajectory_similarity():
    a = np.zeros((10, 2))
    b = np.c_[np.ones(10), np.zeros(10)]
    assert trajectory_mse(a, a) == 0
    assert trajectory_mse(a, b) == 1.0
    assert trajectory_mse(a, b[:5]) == 1.0  # common length
    assert scenario_dissimilarity({"x": a, "y": a}, {"x": b, "y": a}) == 1.0
    assert ego_dissimilarity(a, np.r_[a[:5], b[5:]], until_index=5) == 0.0
