"""rocas.numerics: close to numpy's functions, exact at the special values, and the same bits
whatever numpy's SIMD path (checked in a subprocess with NPY_DISABLE_CPU_FEATURES)."""

from __future__ import annotations

import hashlib
import os
import subprocess
import sys

import numpy as np
import pytest

from rocas import numerics


def _ulps(a: np.ndarray, b: np.ndarray) -> int:
    a = np.asarray(a, dtype=np.float64)
    b = np.asarray(b, dtype=np.float64)
    return int(np.max(np.abs(a.view(np.int64) - b.view(np.int64))))


RNG = np.random.default_rng(7)
WIDE = np.ldexp(RNG.uniform(-1, 1, 20000), RNG.integers(-40, 40, 20000))


def test_exp_log_arctan_within_one_ulp_of_numpy():
    x = np.clip(WIDE, -700, 700)
    assert _ulps(numerics.exp(x), np.exp(x)) <= 1
    pos = np.abs(WIDE) + 1e-300
    assert _ulps(numerics.log(pos), np.log(pos)) <= 1
    assert _ulps(numerics.arctan(WIDE), np.arctan(WIDE)) <= 1
    y = RNG.uniform(-50, 50, WIDE.size)
    assert _ulps(numerics.arctan2(y, WIDE), np.arctan2(y, WIDE)) <= 2


def test_special_values():
    assert numerics.exp(0.0) == 1.0 and numerics.exp(-np.inf) == 0.0 and numerics.exp(800.0) == np.inf
    assert numerics.log(1.0) == 0.0 and numerics.log(0.0) == -np.inf and np.isnan(numerics.log(-1.0))
    for y, x in [(0.0, 0.0), (-0.0, 0.0), (0.0, -0.0), (-0.0, -0.0), (1.0, 0.0), (-1.0, 0.0),
                 (0.0, -1.0), (-0.0, -1.0), (np.inf, 1.0), (1.0, -np.inf), (-np.inf, 2.0)]:
        got, want = numerics.arctan2(y, x), np.arctan2(y, x)
        assert _ulps(got, want) <= 1 and np.signbit(got) == np.signbit(want), (y, x)
    assert numerics.power(0.0, 2.0) == 0.0 and numerics.power(0.0, 0.0) == 1.0
    assert numerics.power(2.0, 10.0) == pytest.approx(1024.0, rel=1e-15)
    assert np.isnan(numerics.exp(np.nan)) and np.isnan(numerics.arctan(np.nan))


def test_tanh_sigmoid_tan_power_are_close():
    x = RNG.uniform(-25, 25, 5000)
    assert np.max(np.abs(numerics.tanh(x) - np.tanh(x))) <= 4e-16
    assert np.max(np.abs(numerics.sigmoid(x) - 1 / (1 + np.exp(-x)))) <= 4e-16
    t = RNG.uniform(-1.5, 1.5, 5000)
    assert np.allclose(numerics.tan(t), np.tan(t), rtol=1e-15, atol=0)
    b, p = RNG.uniform(0, 30, 5000), RNG.uniform(0.1, 8, 5000)
    assert np.allclose(numerics.power(b, p), b ** p, rtol=1e-13, atol=0)


def test_rowdot_is_the_product_and_does_not_depend_on_the_batch():
    x, w = RNG.normal(size=(33, 64)), RNG.normal(size=(64, 16))
    full = numerics.rowdot(x, w)
    assert np.allclose(full, x @ w, rtol=1e-12, atol=1e-12)
    assert all(np.array_equal(numerics.rowdot(x[i:i + 1], w), full[i:i + 1]) for i in range(33))


def _bits(a: np.ndarray) -> np.ndarray:
    return np.asarray(a, dtype=np.float64).view(np.int64)


def test_an_element_gets_the_same_bits_with_or_without_special_values_beside_it():
    # exp and log skip their special-case passes when no argument needs them; a batch with
    # one special argument must give every other element the same bits
    x = np.ldexp(RNG.uniform(-1, 1, 5000), RNG.integers(-30, 10, 5000))
    for special in (np.nan, 800.0, -800.0, np.inf):
        both = numerics.exp(np.append(x, special))
        assert np.array_equal(_bits(both[:-1]), _bits(numerics.exp(x)))
    pos = np.abs(x) + 1e-300
    for special in (0.0, -1.0, np.nan, np.inf):
        both = numerics.log(np.append(pos, special))
        assert np.array_equal(_bits(both[:-1]), _bits(numerics.log(pos)))
    assert np.array_equal(_bits(numerics.exp(x[:7].reshape(7, 1))), _bits(numerics.exp(x[:7]))[:, None])


def test_arctan_is_arctan2_over_one_bit_for_bit():
    # control fuses arctan into an arctan2 call with x = 1
    v = np.concatenate([WIDE, [0.0, -0.0, 1.0, -1.0, 1e-310, np.inf, -np.inf, 1 + 2**-52]])
    assert np.array_equal(_bits(numerics.arctan(v)), _bits(numerics.arctan2(v, np.ones_like(v))))


def test_rowdot_sums_a_large_batch_in_the_same_order_as_a_small_one():
    # from _ROWDOT_CHUNK_ROWS rows on, rowdot sums in chunks of rows; every row must keep its
    # bits, also with one output column (the brake classifier's logit), whose sums numpy takes
    # pairwise: summed term by term from 128 rows on, they differed in 258 of 300 rows
    for h in (16, 1):
        x, w = RNG.normal(size=(300, 64)), RNG.normal(size=(64, h))
        x[5, :] = 0.0
        x[6, ::2] = -0.0
        w[:, h // 2] = -np.abs(w[:, h // 2])  # row 5: a sum of -0.0 terms, which is +0.0
        big = numerics.rowdot(x, w)
        assert x.shape[0] > numerics._ROWDOT_CHUNK_ROWS
        small = np.concatenate([numerics.rowdot(x[i:i + 10], w) for i in range(0, 300, 10)])
        assert np.array_equal(_bits(big), _bits(small))
        assert np.array_equal(_bits(numerics.rowdot(x[7:8], w)), _bits(big[7:8]))
        assert not np.signbit(big[5, h // 2])
        # a feature zero in every row of one batch and not of another: the same bits
        x[:, 3] = 0.0
        x[0, 3] = 1e-3
        # (with one column, skipping such a feature regrouped numpy's pairwise sums: 9 of 10
        # rows differed)
        whole = numerics.rowdot(x, w)
        assert np.array_equal(_bits(numerics.rowdot(x[1:11], w)), _bits(whole[1:11]))


def _rowdot_every_term(x: np.ndarray, w: np.ndarray) -> np.ndarray:
    return (x[:, :, None] * w[None, :, :]).sum(axis=1)


def test_rowdot_skips_all_zero_features_without_changing_a_bit():
    for rows in (3, 200):
        x = RNG.normal(size=(rows, 64))
        x[:, ::3] = 0.0
        x[:, 1::7] = -0.0
        w = RNG.normal(size=(64, 8))
        w[2::3, 5] = -w[2::3, 5]
        assert np.array_equal(_bits(numerics.rowdot(x, w)), _bits(_rowdot_every_term(x, w)))
        # all features zero: every sum is +0.0, also where every term is -0.0
        z = np.zeros((rows, 64))
        assert np.array_equal(_bits(numerics.rowdot(z, -np.abs(w))),
                              _bits(_rowdot_every_term(z, -np.abs(w))))
        # a non-finite weight times a zero feature is NaN, as in the full sum
        w_inf = w.copy()
        w_inf[0, 0] = np.inf
        with np.errstate(invalid="ignore"):
            assert np.isnan(numerics.rowdot(x, w_inf)[:, 0]).all()


def _in_small_calls(f, *args: np.ndarray) -> np.ndarray:
    """f over arrays of at most 16 elements (numerics' scalar path), concatenated."""
    n = args[0].size
    return np.concatenate([np.atleast_1d(f(*(a[i:i + 16] for a in args)))
                           for i in range(0, n, 16)])


def test_small_arrays_get_the_bits_of_the_array_path():
    # numerics evaluates arrays of at most 16 finite elements one float at a time in Python;
    # every element must get the bits the array path gives it
    eighths = np.arange(0, 17) / 16.0  # arctan's table boundaries (ties of t * 8)
    special = np.array([0.0, -0.0, 1.0, -1.0, 0.5, 1e-310, -1e-310, 40.0, -40.0, 708.0, -708.0,
                        np.pi, 1e300, -1e300])
    x = np.concatenate([WIDE, RNG.uniform(-12, 12, 6000), eighths, -eighths, 1 / eighths[1:],
                        special])
    y = np.concatenate([RNG.uniform(-50, 50, WIDE.size), RNG.normal(size=6000), eighths[::-1],
                        eighths, -eighths[1:], special[::-1]])
    e = np.clip(x, -708.0, 708.0)
    pos = np.abs(x) + 1e-300
    cases = [(numerics.exp, (e,)), (numerics.log, (pos,)), (numerics.log_positive, (pos,)),
             (numerics.arctan, (x,)), (numerics.arctan2, (y, x)), (numerics.arctan2, (x, y)),
             (numerics.tanh, (x,)), (numerics.sigmoid, (np.clip(x, -700, 700),)),
             (numerics.power, (pos[:3000], np.abs(y[:3000]) % 8))]
    for f, args in cases:
        whole = np.asarray(f(*args))
        assert whole.size > 16
        small = _in_small_calls(f, *args)
        assert np.array_equal(whole.view(np.int64), small.view(np.int64)), f.__name__
    for yy in (0.0, -0.0, 1.0, -1.0):
        for xx in (0.0, -0.0, 1.0, -1.0):
            got = numerics.arctan2(np.array([yy]), np.array([xx]))
            want = numerics.arctan2(np.full(17, yy), np.full(17, xx))[:1]
            assert got.view(np.int64)[0] == want.view(np.int64)[0], (yy, xx)
    zeros = np.tile([0.0, -0.0], 20)  # planning keeps arctan(+-0.0) = +-0.0 without a call
    for z in (zeros, zeros[:2]):
        assert np.array_equal(numerics.arctan(z).view(np.int64), z.view(np.int64))
    assert type(numerics.exp(0.5)) is np.float64 and numerics.arctan2(np.ones((2, 3)), 1.0).shape == (2, 3)


def test_scalars_stay_scalars():
    assert np.ndim(numerics.exp(1.0)) == 0 and np.ndim(numerics.arctan2(1.0, 2.0)) == 0


_CHILD = """
import hashlib, numpy as np
from rocas import numerics as n
rng = np.random.default_rng(3)
x = np.ldexp(rng.uniform(-1, 1, 50000), rng.integers(-28, 28, 50000)); y = rng.normal(size=50000)
out = [n.exp(np.clip(x, -700, 700)), n.log(np.abs(x)), n.arctan(x), n.arctan2(y, x), n.tanh(y),
       n.tan(y), n.power(np.abs(x), np.abs(y)), n.rowdot(x[:4096].reshape(64, 64), y[:4096].reshape(64, 64))]
print(hashlib.sha256(b"".join(a.tobytes() for a in out)).hexdigest())
"""


def test_the_same_bits_on_every_simd_path():
    info = np.lib._utils_impl._opt_info()
    dispatched = [tok.rstrip("*") for tok in info.split() if tok.endswith("*")]
    if not dispatched:
        pytest.skip(f"numpy dispatches to no SIMD path above its baseline here ({info})")
    digests = set()
    for disabled in ("", " ".join(dispatched[-1:]), " ".join(dispatched)):
        env = dict(os.environ, NPY_DISABLE_CPU_FEATURES=disabled)
        done = subprocess.run([sys.executable, "-c", _CHILD], env=env, capture_output=True,
                              text=True, timeout=120, check=True)
        digests.add(done.stdout.strip())
    assert len(digests) == 1
    assert len(next(iter(digests))) == len(hashlib.sha256().hexdigest())
