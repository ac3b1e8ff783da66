"""Elementary functions whose float64 results are the same on every machine.

numpy dispatches ``exp``, ``log``, ``arctan``, ``arctan2``, ``tan``, ``tanh`` and ``power`` to
SIMD kernels chosen at run time by the CPU (AVX2, AVX-512, or none), and those kernels round
differently in the last bit; ``@``/``matmul``/``dot`` go to a BLAS whose kernel
(``OPENBLAS_CORETYPE``) changes the order of a sum. One ulp is enough to move a simulated
reference across a decision threshold, and with it an analysis's answer. The simulator and the
stacks therefore use the functions here, which are built only from operations IEEE 754 rounds
exactly (``+ - * /``, ``sqrt``, ``rint``, ``ldexp``, ``frexp``, comparisons), evaluated
elementwise in a fixed order, so they give the same bits whatever the SIMD path or BLAS kernel.
``np.sin``, ``np.cos`` and ``np.hypot`` are used as they are: they do not depend on the
dispatch path (``tests/test_numerics.py`` checks this in subprocesses).

The algorithms and coefficients are the classic ones of fdlibm (Sun Microsystems, 1993): range
reduction to a small interval, then a fixed polynomial. Each function is within 1-2 ulp of the
correctly rounded result over the ranges the simulator uses; what matters more here is that the
error is the same everywhere.

Every function takes array-likes and returns float64 arrays (or a float64 scalar for scalar
input, as numpy does).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

__all__ = ["arctan", "arctan2", "exp", "log", "log_positive", "power", "rowdot", "sigmoid", "tan", "tanh"]

_LN2_HI = 6.93147180369123816490e-01  # ln 2, high part: k * _LN2_HI is exact for |k| < 2**11
_LN2_LO = 1.90821492927058770002e-10
_INV_LN2 = 1.44269504088896338700e00
_EXP_P = (1.66666666666666019037e-01, -2.77777777770155933842e-03, 6.61375632143793436117e-05,
          -1.65339022054652515390e-06, 4.13813679705723846039e-08)
_EXP_MAX, _EXP_MIN = 709.782712893383973096, -745.13321910194110842
_LOG_LG = (6.666666666666735130e-01, 3.999999999940941908e-01, 2.857142874366239149e-01,
           2.222219843214978396e-01, 1.818357216161805012e-01, 1.531383769920937332e-01,
           1.479819860511658591e-01)
_SQRT2 = 1.41421356237309514547
# atan(k/8) for k = 0..8 as a high part and a low correction (computed to 50 digits)
_ATAN_EIGHTHS_HI = np.array([
    0.0, 0.12435499454676144, 0.24497866312686414, 0.35877067027057225, 0.4636476090008061,
    0.5585993153435624, 0.6435011087932844, 0.7188299996216245, 0.7853981633974483])
_ATAN_EIGHTHS_LO = np.array([
    0.0, -3.1253241424539383e-18, 1.0698755618734451e-17, -2.4623815582638635e-17,
    2.2698777452961687e-17, -5.4556305485916264e-18, 1.5834785051444286e-17,
    -2.1478388444456983e-17, 3.061616997868383e-17])
_TINY = 1e-300
_PI_HI = 3.14159265358979311600e00
_PI_LO = 1.22464679914735317720e-16
_PI_2_HI = 1.57079632679489655800e00
_PI_2_LO = 6.12323399573676603587e-17


_EXP_PLAIN = 708.0  # |x| <= this: no clipping, no overflow or underflow to handle
_max = np.maximum.reduce
_min = np.minimum.reduce


def _max_abs(x: np.ndarray) -> float:
    """Largest |x| (NaN if any element is NaN)."""
    return _max(np.abs(x), axis=None)


def _out(result: np.ndarray, scalar: bool) -> np.ndarray:
    return result[()] if scalar else result


# Small arrays (a batch of one: a few obstacles, one ego) go through the same formulas one
# element at a time in Python floats: each step is the same IEEE 754 double operation
# (+ - * /, comparisons, abs, copysign, frexp, ldexp; ``round`` rounds half to even as
# ``np.rint`` does), so the bits are those of the array path (tests/test_numerics.py compares
# them), at a fraction of the cost of some forty numpy calls on a few elements. Arguments
# that need a special case (non-finite, out of range) take the array path.
_SMALL = 16


def _small(xa: np.ndarray) -> list[float] | None:
    """The elements of a small array as Python floats, or None (use the array path)."""
    if 0 < xa.size <= _SMALL:
        vals = xa.ravel().tolist()
        for v in vals:
            if not math.isfinite(v):
                return None
        return vals
    return None


def _from_small(vals: list[float], xa: np.ndarray) -> np.ndarray:
    """Scalar results back into the shape (and scalar-ness) of ``xa``."""
    out = np.array(vals, dtype=np.float64).reshape(xa.shape)
    return out[()] if xa.ndim == 0 else out


def _exp_scalar(x: float) -> float:
    """exp's arithmetic on one float with |x| <= _EXP_PLAIN."""
    k = float(round(x * _INV_LN2))
    return math.ldexp(_exp_reduced(x, k), int(k))


def _exp_reduced(x: Any, k: Any) -> Any:
    """e**(x - k ln 2), |x - k ln 2| <= ln(2) / 2: the same IEEE operations on Python floats
    (the small-array path) or float64 arrays of one shape (the array path)."""
    hi = x - k * _LN2_HI
    lo = k * _LN2_LO
    r = hi - lo
    t = r * r
    p = _EXP_P
    c = r - t * (p[0] + t * (p[1] + t * (p[2] + t * (p[3] + t * p[4]))))
    return 1.0 - ((lo - (r * c) / (2.0 - c)) - hi)


def _log_scalar(x: float) -> float:
    """_log_core's arithmetic on one positive finite float."""
    m, e = math.frexp(x)
    big = m < 0.5 * _SQRT2
    if big:
        m = 2.0 * m
    return _log_reduced(m, float(e - 1 if big else e))


def _log_reduced(m: Any, k: Any) -> Any:
    """log(m) + k ln 2 for m in [sqrt(2)/2, sqrt(2)): the same IEEE operations on Python floats
    (the small-array path) or float64 arrays of one shape (the array path)."""
    f = m - 1.0
    s = f / (2.0 + f)
    z = s * s
    w = z * z
    g = _LOG_LG
    t1 = w * (g[1] + w * (g[3] + w * g[5]))
    t2 = z * (g[0] + w * (g[2] + w * (g[4] + w * g[6])))
    r = t2 + t1
    hfsq = 0.5 * f * f
    return k * _LN2_HI - ((hfsq - (s * (hfsq + r) + k * _LN2_LO)) - f)


def exp(x: np.ndarray | float) -> np.ndarray:
    """e**x, elementwise. Shape: as ``x``."""
    xa = np.asarray(x, dtype=np.float64)
    vals = _small(xa)
    if vals is not None and max(map(abs, vals)) <= _EXP_PLAIN:
        return _from_small([_exp_scalar(v) for v in vals], xa)
    scalar = xa.ndim == 0
    # one reduction tells whether any argument needs the special cases (NaN fails the test);
    # without them the result is the same arithmetic minus five passes over the array
    plain = xa.size == 0 or bool(_max_abs(xa) <= _EXP_PLAIN)
    xc = xa if plain else np.minimum(np.maximum(xa, _EXP_MIN), _EXP_MAX)
    k = np.rint(xc * _INV_LN2)
    y = _exp_reduced(xc, k)
    if plain:
        return _out(np.ldexp(y, k.astype(np.int64)), scalar)
    out = np.ldexp(y, np.where(k == k, k, 0.0).astype(np.int64))  # NaN: any exponent
    out = np.where(xa > _EXP_MAX, np.inf, out)
    out = np.where(xa < _EXP_MIN, 0.0, out)
    out = np.where(np.isnan(xa), np.nan, out)
    return _out(out, scalar)


def sigmoid(x: np.ndarray | float) -> np.ndarray:
    """1 / (1 + e**-x), elementwise. Shape: as ``x``."""
    return 1.0 / (1.0 + exp(-np.asarray(x, dtype=np.float64)))


def log(x: np.ndarray | float) -> np.ndarray:
    """Natural logarithm, elementwise (``-inf`` at 0, NaN below). Shape: as ``x``."""
    xa = np.asarray(x, dtype=np.float64)
    vals = _small(xa)
    if vals is not None and min(vals) > 0.0:
        return _from_small([_log_scalar(v) for v in vals], xa)
    scalar = xa.ndim == 0
    # all arguments positive and finite (NaN fails both tests): no special cases to mask
    plain = xa.size == 0 or bool((_min(xa, axis=None) > 0.0) & (_max(xa, axis=None) < np.inf))
    ok = None if plain else np.isfinite(xa) & (xa > 0.0)
    out = _log_core(xa if plain else np.where(ok, xa, 1.0))
    if plain:
        return _out(out, scalar)
    out = np.where(xa == 0.0, -np.inf, out)
    out = np.where(xa == np.inf, np.inf, out)
    out = np.where((xa < 0.0) | np.isnan(xa), np.nan, out)
    return _out(out, scalar)


def log_positive(x: np.ndarray) -> np.ndarray:
    """:func:`log` of a float64 array whose every element the caller knows to be positive and
    finite (the same arithmetic without the test for special cases). Shape: as ``x``."""
    vals = _small(x)
    if vals is not None:
        return _from_small([_log_scalar(v) for v in vals], x)
    return _log_core(x)


def _log_core(xa: np.ndarray) -> np.ndarray:
    """log of positive finite float64 values."""
    m, e = np.frexp(xa)  # xa = m * 2**e, 0.5 <= m < 1
    big = m < 0.5 * _SQRT2  # move m into [sqrt(2)/2, sqrt(2))
    m = np.where(big, 2.0 * m, m)
    k = (e - big.astype(e.dtype)).astype(np.float64)
    return _log_reduced(m, k)


def power(base: np.ndarray | float, exponent: np.ndarray | float) -> np.ndarray:
    """base**exponent for base >= 0 (0**p is 0 for p > 0 and 1 for p == 0). Shapes broadcast."""
    b = np.asarray(base, dtype=np.float64)
    p = np.asarray(exponent, dtype=np.float64)
    scalar = b.ndim == 0 and p.ndim == 0
    safe = np.where(b > 0.0, b, 1.0)
    out = exp(p * log(safe))
    out = np.where(b == 0.0, np.where(p == 0.0, 1.0, np.where(p > 0.0, 0.0, np.inf)), out)
    out = np.where(b < 0.0, np.nan, out)
    return _out(np.asarray(out), scalar)


def _arctan_unit(t: np.ndarray) -> np.ndarray:
    """atan(t) for t in [0, 1]: t = c + d with c = k/8 the nearest eighth, so that
    atan(t) = atan(c) + atan(u) with u = (t - c) / (1 + c t), |u| <= 1/16, and atan(u) is its
    Taylor series to u**13 (the next term is below 1e-18 relative)."""
    k = np.fmin(np.rint(t * 8.0), 8.0)  # fmin: NaN -> 8, whose u is NaN again
    c = k * 0.125
    u = (t - c) / (1.0 + c * t)
    z = u * u
    q = z * (-1.0 / 3 + z * (1.0 / 5 + z * (-1.0 / 7 + z * (1.0 / 9 + z * (-1.0 / 11 + z / 13)))))
    i = k.astype(np.intp)
    return _ATAN_EIGHTHS_HI[i] + ((u + u * q) + _ATAN_EIGHTHS_LO[i])


def _arctan_unit_scalar(t: float) -> float:
    """_arctan_unit's arithmetic on one float in [0, 1]."""
    k = min(float(round(t * 8.0)), 8.0)
    c = k * 0.125
    u = (t - c) / (1.0 + c * t)
    z = u * u
    q = z * (-1.0 / 3 + z * (1.0 / 5 + z * (-1.0 / 7 + z * (1.0 / 9 + z * (-1.0 / 11 + z / 13)))))
    i = int(k)
    return _ATAN_HI_LIST[i] + ((u + u * q) + _ATAN_LO_LIST[i])


_ATAN_HI_LIST = _ATAN_EIGHTHS_HI.tolist()
_ATAN_LO_LIST = _ATAN_EIGHTHS_LO.tolist()


def _arctan2_scalar(y: float, x: float) -> float:
    """arctan2's arithmetic on one finite pair."""
    ay, ax = abs(y), abs(x)
    den = ax if ax >= ay else ay
    a = _arctan_unit_scalar((ax if ax <= ay else ay) / (den if den >= _TINY else _TINY))
    if ay > ax:
        a = _PI_2_HI - (a - _PI_2_LO)
    if math.copysign(1.0, x) < 0.0:
        a = _PI_HI - (a - _PI_LO)
    return math.copysign(a, y)


def arctan(x: np.ndarray | float) -> np.ndarray:
    """Arc tangent in [-pi/2, pi/2], elementwise. Shape: as ``x``."""
    xa = np.asarray(x, dtype=np.float64)
    vals = _small(xa)
    if vals is not None:
        return _from_small([_arctan_scalar(v) for v in vals], xa)
    scalar = xa.ndim == 0
    ax = np.abs(xa)
    a = _arctan_unit(np.minimum(ax, 1.0 / np.maximum(ax, _TINY)))  # atan(1/x) = pi/2 - atan(x)
    a = np.where(ax > 1.0, _PI_2_HI - (a - _PI_2_LO), a)
    return _out(np.copysign(a, xa), scalar)


def _arctan_scalar(x: float) -> float:
    """arctan's arithmetic on one finite float."""
    ax = abs(x)
    inv = 1.0 / (ax if ax >= _TINY else _TINY)
    a = _arctan_unit_scalar(ax if ax <= inv else inv)
    if ax > 1.0:
        a = _PI_2_HI - (a - _PI_2_LO)
    return math.copysign(a, x)


def arctan2(y: np.ndarray | float, x: np.ndarray | float) -> np.ndarray:
    """Angle of the point (x, y) in [-pi, pi], elementwise, with C's signed-zero conventions
    (both infinite: not handled). Shapes broadcast."""
    ya = np.asarray(y, dtype=np.float64)
    xa = np.asarray(x, dtype=np.float64)
    if ya.shape == xa.shape:
        yv = _small(ya)
        xv = _small(xa) if yv is not None else None
        if xv is not None:
            return _from_small([_arctan2_scalar(b, a) for b, a in zip(yv, xv, strict=True)], ya)
    scalar = ya.ndim == 0 and xa.ndim == 0
    ay, ax = np.abs(ya), np.abs(xa)
    den = np.maximum(ax, ay)
    a = _arctan_unit(np.minimum(ax, ay) / np.maximum(den, _TINY))  # in [0, pi/4]
    a = np.where(ay > ax, _PI_2_HI - (a - _PI_2_LO), a)
    a = np.where(np.signbit(xa), _PI_HI - (a - _PI_LO), a)
    return _out(np.copysign(a, ya), scalar)


def tan(x: np.ndarray | float) -> np.ndarray:
    """Tangent, elementwise, as sin/cos (both dispatch-independent). Shape: as ``x``."""
    xa = np.asarray(x, dtype=np.float64)
    return np.sin(xa) / np.cos(xa)


def tanh(x: np.ndarray | float) -> np.ndarray:
    """Hyperbolic tangent, elementwise. Shape: as ``x``.

    Absolute error below 2e-16 (relative error grows for |x| < 1e-8, where tanh(x) ~ x).
    """
    xa = np.asarray(x, dtype=np.float64)
    vals = _small(xa)
    if vals is not None:
        out = []
        for v in vals:
            e = _exp_scalar(2.0 * min(abs(v), 40.0))
            out.append(math.copysign(1.0 - 2.0 / (e + 1.0), v))
        return _from_small(out, xa)
    scalar = xa.ndim == 0
    ax = np.minimum(np.abs(xa), 40.0)  # tanh(40) == 1.0 in float64
    out = 1.0 - 2.0 / (exp(2.0 * ax) + 1.0)
    out = np.copysign(out, xa)
    out = np.where(np.isnan(xa), np.nan, out)
    return _out(out, scalar)


_ROWDOT_CHUNK_ROWS = 64  # rows summed in one (N, F, H) product; larger batches go in chunks


def rowdot(x: np.ndarray, w: np.ndarray) -> np.ndarray:
    """``x @ w`` without BLAS: (N, F) x (F, H) -> (N, H), summed over F in a fixed order.

    Each row's result depends only on that row, so it is the same whatever N is.
    """
    x = np.asarray(x, dtype=np.float64)
    w = np.asarray(w, dtype=np.float64)
    # A feature that is zero in every row adds x * w = +-0.0 to each sum, and that changes no
    # bit: a sum starts at +0.0 and, rounding to nearest, only -0.0 + -0.0 gives -0.0, so a
    # sum is never -0.0 and s + (+-0.0) == s. Such features are skipped (a camera view is
    # mostly empty columns); with a non-finite weight, 0 * w would be NaN, so not then. Only
    # when the sums run term by term (H > 1, below): numpy's pairwise sum of a single column
    # groups the terms by position, so dropping one would regroup the others.
    if x.shape[0] and w.shape[0] and w.shape[1] > 1:
        used = np.logical_or.reduce(x != 0.0, axis=0)
        if not used.all() and np.isfinite(w).all():
            x, w = x[:, used], w[used]
    if x.shape[0] <= _ROWDOT_CHUNK_ROWS or w.shape[0] == 0:
        return _rowdot_rows(x, w)
    # a large batch in chunks of rows (its (N, F, H) temporary would not fit in the cache),
    # each summed as a small batch is: a row's sums never depend on the rows beside it
    out = np.empty((x.shape[0], w.shape[1]))
    for i in range(0, x.shape[0], _ROWDOT_CHUNK_ROWS):
        out[i:i + _ROWDOT_CHUNK_ROWS] = _rowdot_rows(x[i:i + _ROWDOT_CHUNK_ROWS], w)
    return out


def _rowdot_rows(x: np.ndarray, w: np.ndarray) -> np.ndarray:
    """(N, F) x (F, H) -> (N, H) through one (N, F, H) product reduced over F.

    numpy reduces the middle axis F-sequentially for each (n, h) when H > 1, and with its
    pairwise sum over each row's F terms when H == 1 (the axis is then the contiguous one):
    either way the order depends on F and H only, not on N, and no CPU feature or BLAS
    kernel changes it.
    """
    return (x[:, :, None] * w[None, :, :]).sum(axis=1)
