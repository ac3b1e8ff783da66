import numpy as np
import pytest
import ruptures

from rocas.analysis.changepoints import ChangePointConfig, detect, median, median_filter, pelt_l2


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


def test_pelt_l2_finds_ruptures_change_points_exactly():
    """rocas's numpy PELT returns what ruptures' C solver (KernelCPD, linear kernel: exact PELT
    for the l2 cost) returns, on noisy steps, MDR-like series full of ties, and rare spikes."""
    rng = np.random.default_rng(0)
    for trial in range(400):
        n = int(rng.integers(2, 160))
        kind = trial % 4
        if kind == 0:
            y = rng.normal(0, 0.05, n) + (np.arange(n) > rng.integers(0, n))
        elif kind == 1:
            y = rng.integers(0, 3, n) / 4.0
        elif kind == 2:
            y = np.round(rng.random(n), 1)
        else:
            y = np.where(rng.random(n) < 0.1, 1.0, 0.0)
        pen = float(rng.choice([1e-6, 1e-3, 0.05, 0.5, 3.0]))
        min_size = int(rng.choice([1, 1, 2, 3]))
        if n < 2 * min_size:
            continue
        expected = ruptures.KernelCPD(kernel="linear", min_size=min_size, jump=1).fit(
            y.reshape(-1, 1)).predict(pen=pen)
        assert pelt_l2(y, pen, min_size) == expected, (trial, n, pen, min_size)


def test_pelt_l2_is_the_l2_optimum():
    """Against ruptures' Pelt with the l2 cost (the segmentation the paper's PELT defines)."""
    for seed in range(3):
        y, _ = _step(n=120, at=70, noise=0.05, seed=seed)
        slow = ruptures.Pelt(model="l2", min_size=2, jump=1).fit(y.reshape(-1, 1)).predict(pen=0.05)
        assert pelt_l2(y, 0.05, 2) == slow
    assert pelt_l2(np.zeros(0), 1.0) == []
    assert pelt_l2(np.array([0.0, 0.0, 1.0, 1.0]), 0.01) == [2, 4]


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


def test_running_median_and_median_agree_with_numpy_to_the_bit():
    """The running median truncates its windows at the ends, as np.nanmedian over NaN-padded
    windows does; both medians take the mean of the two middle values of an even count."""
    rng = np.random.default_rng(3)
    for trial in range(400):
        n, width = int(rng.integers(3, 30)), int(rng.integers(2, 9))
        values = rng.random(n) if trial % 2 else rng.integers(0, 4, n) / 3.0
        w = width + 1 - width % 2
        padded = np.concatenate([np.full(w // 2, np.nan), values, np.full(w // 2, np.nan)])
        expected = np.nanmedian(np.lib.stride_tricks.sliding_window_view(padded, w), axis=1)
        assert np.array_equal(median_filter(values, width), expected)
        k = int(rng.integers(1, n + 1))
        assert median(values[:k]) == float(np.median(values[:k]))
