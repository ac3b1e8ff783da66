import numpy as np
import pytest
import ruptures

from rocas.analysis.changepoints import ChangePointConfig, detect, median_filter


def _step(n=200, at=120, low=0.1, high=0.5, noise=0.02, seed=0):
    rng = np.random.default_rng(seed)
    y = np.where(np.arange(n) < at, low, high) + rng.normal(0, noise, n)
    return np.clip(y, 0, 1), np.arange(n) * 0.1


def test_finds_a_step_at_its_time():
    y, t = _step()
    cps = detect(y, t, ChangePointConfig())
    assert cps.first_s == pytest.approx(12.0, abs=0.15)


def test_noise_alone_has_no_change_point():
    for seed in range(5):
        y, t = _step(high=0.1, seed=seed)
        assert detect(y, t, ChangePointConfig()).first_s is None


def test_identical_runs_have_no_change_point():
    assert detect(np.zeros(100), np.arange(100) * 0.1, ChangePointConfig()).first_s is None


def test_isolated_impulses_are_not_change_points():
    y = np.full(150, 0.3)
    y[[0, 40, 41, 90, 120, 149]] = 1.0  # messages that slipped into a neighbouring bin
    assert detect(y, np.arange(150) * 0.1, ChangePointConfig()).first_s is None


def test_penalty_scales_with_baseline_noise():
    quiet, t = _step(noise=0.01)
    noisy, _ = _step(noise=0.1)
    cfg = ChangePointConfig()
    assert detect(noisy, t, cfg).penalty > detect(quiet, t, cfg).penalty


def test_penalty_is_the_documented_formula_of_the_reported_noise():
    import math

    y, t = _step(noise=0.05)
    cfg = ChangePointConfig()
    cp = detect(y, t, cfg)
    base = y[t < t[0] + cfg.baseline_s]
    assert cp.noise_std == pytest.approx(max(np.std(base), np.std(np.diff(y)) / math.sqrt(2)))
    assert cp.penalty == pytest.approx(cfg.penalty_scale * max(cp.noise_std, cfg.noise_floor) ** 2
                                       * math.log(len(y)))


def test_fixed_penalty_overrides_the_formula():
    y, t = _step()
    assert detect(y, t, ChangePointConfig(penalty=1e6)).first_s is None
    assert detect(y, t, ChangePointConfig(penalty=0.5)).penalty == 0.5


def test_kernel_linear_is_exact_pelt_l2():
    """The fast solver computes the same segmentation as ruptures' Pelt with the l2 cost."""
    for seed in range(3):
        y, _ = _step(n=120, at=70, noise=0.05, seed=seed)
        y = y.reshape(-1, 1)
        fast = ruptures.KernelCPD(kernel="linear", min_size=2, jump=1).fit(y).predict(pen=0.05)
        slow = ruptures.Pelt(model="l2", min_size=2, jump=1).fit(y).predict(pen=0.05)
        assert fast == slow


def test_median_filter_removes_impulses_and_keeps_steps():
    y = np.array([0, 0, 0, 1, 0, 0, 0, 5, 5, 5, 5, 5], dtype=float)
    out = median_filter(y, 5)
    assert out[3] == 0
    assert list(np.nonzero(out >= 5)[0]) == [7, 8, 9, 10, 11]
    assert median_filter(y, 1) is y



# the traffic-light channel of catalog entry A10 against a reference with the side light held at
# yellow: a far light differs slightly from 1.9 to 4.4 s; at 7.0 s the selected light's colour
# differs (one field), from 7.1 s its confidence too, at 8.0 s the ego has stopped elsewhere
A10_TRAFFIC_LIGHT = [0.0] * 19 + [0.025] * 26 + [0.0] * 25 + [0.05] + [0.1] * 9 + [0.75] * 5


def test_a_change_that_builds_up_is_dated_at_its_onset():
    values = np.array(A10_TRAFFIC_LIGHT)
    cps = detect(values, np.arange(len(values)) * 0.1, ChangePointConfig())
    assert cps.indices[0] == 70


def test_onset_ignores_a_noisy_baseline_and_stays_within_the_median_reach():
    rng = np.random.default_rng(3)
    values = np.concatenate([rng.normal(0.2, 0.01, 60), [0.205], np.full(20, 0.6)])
    cps = detect(values, np.arange(len(values)) * 0.1, ChangePointConfig())
    assert cps.indices[0] == 61  # 0.205 is within the baseline's noise
    far = np.array([0.0] * 40 + [0.02] * 6 + [0.5] * 20)
    assert detect(far, np.arange(len(far)) * 0.1, ChangePointConfig()).indices[0] >= 44
