"""The highway catalog's ground truth, checked by simulation."""

import numpy as np
import pytest

pytest.importorskip("highway_env")

from rocas.stacks.highway.accidents import entries, entry  # noqa: E402
from rocas.stacks.highway.params import parameters  # noqa: E402
from rocas.stacks.highway.world import simulate  # noqa: E402

FIXABLE = [e for e in entries() if e.parameter]


def test_the_catalog_spans_six_accidents_in_three_environments():
    es = entries()
    assert len(es) >= 6
    assert len({e.scene.env_id for e in es}) >= 3
    assert any(not e.parameter for e in es)
    assert entry("h01").key == "h01_crawling_car_weak_brakes"


@pytest.mark.parametrize("e", FIXABLE, ids=lambda e: e.key)
def test_the_fix_avoids_the_accident_and_keeps_the_drive_before_it(e):
    accident = simulate(e.scene, e.params, e.seed)
    fixed = simulate(e.scene, {**e.params, e.parameter: e.fix}, e.seed)
    assert accident.accident and not fixed.accident
    assert e.parameter.split(".")[0] == e.module
    # the drive before the accident is kept: over its first quarter the fixed ego stays within
    # 1 m of the accident's, and the two start identical
    k = max(2, int(np.searchsorted(accident.times, accident.accident_t_s / 4)))
    apart = np.hypot(*(accident.ego[:k, :2] - fixed.ego[:k, :2]).T)
    assert apart[0] == 0.0 and apart.max() < 1.0


@pytest.mark.slow
def test_no_parameter_at_either_end_of_its_range_avoids_the_unfixable_accident():
    for e in (e for e in entries() if not e.parameter):
        for p in parameters():
            for value in (p.low, p.high):
                assert simulate(e.scene, {p.full_name: value}, e.seed).accident, (e.key, p)
