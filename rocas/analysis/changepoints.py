"""Change points of an MDR series with PELT (exact, l2 cost).

:func:`pelt_l2` is exact PELT for the l2 (change in mean) cost, with numpy doing each step's
work over the admissible segment starts. It performs the same floating-point operations in
the same order as ``ruptures.KernelCPD(kernel="linear")`` (running sums of products, updated
as the series grows), so it returns the same change points bit for bit (a test compares them), and
those are the change points of ``ruptures.Pelt(model="l2")``. It replaces ruptures at run
time because ``import ruptures`` imports scipy.stats, which cost more than a whole diff of a
30 s recording pair.

Before PELT the series passes through a running median of ``smooth_bins`` bins (1 turns it
off). A message that falls into the neighbouring bin in one recording only is unpaired and
scores 1 in two adjacent bins: an impulse, not a change of regime. A median filter removes
impulses up to half its width while keeping step edges (and so change point times) exactly.

The penalty follows the paper's argument that the first seconds of two compared runs are
alike, so their MDR is the channel's baseline noise:

    noise**2 = max(var(baseline), var(diff(series)) / 2, noise_floor**2)
    penalty  = penalty_scale * noise**2 * ln(n)

where ``baseline`` is the part of the series in its first ``baseline_s`` seconds and ``n``
the series length (a BIC-like penalty scaled by the channel's own noise). The second term
estimates bin-to-bin noise over the whole series from first differences: a level shift adds
a single large difference and barely moves it, while isolated spikes (a message that falls
into the neighbouring bin in one recording and so goes unpaired) raise it, so rare spikes a
short baseline happened not to contain do not become change points. The floor keeps a
noiseless series (identical runs) from making every wiggle a change point. An explicit
``penalty`` replaces the formula.

A change that builds up over a bin or two (a channel whose first differing message differs in
fewer fields than the ones after it: 0, 0.05, 0.1, ...) is placed by the l2 cost at its larger
step. Each change point is therefore moved back to the onset of the run of bins just before it
that have already left the previous segment's level, in the direction of the change: raw values
beyond that segment's level by more than three of its standard deviations (a deterministic
baseline has none, so any departure counts), at most ``smooth_bins // 2`` bins, the most the
running median can delay an edge.

A change point PELT places is then judged against the noise the two runs show *before* it
(Finding 6 of issue 21: on long noisy pairs PELT found level changes in the noise itself): the
new segment's level (median of the smoothed series up to the next change point) must differ
from the level before it (median of the raw series since the last kept change point) by more
than ``significance`` standard deviations of those raw values. A deterministic stretch
(standard deviation 0) keeps any change, as before; a change point that fails is dropped and
its stretch joins the next one's "before".
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class ChangePointConfig:
    """How change points are detected.

    Attributes:
        baseline_s: length of the baseline window at the start of the series [s].
        penalty_scale: multiplier of the noise-derived penalty (dimensionless).
        noise_floor: smallest baseline standard deviation assumed [MDR units].
        penalty: fixed penalty; None derives it from the baseline.
        min_size: fewest bins in a segment (1: a one-bin ramp step does not pull the change
            point a bin early; impulses are the median filter's job).
        smooth_bins: width of the running median applied first (odd; 1 = none).
        significance: how many standard deviations of the raw values before a change point
            its new level must lie away from theirs (0 keeps every change point PELT finds).
    """

    baseline_s: float = 3.0
    penalty_scale: float = 3.0
    noise_floor: float = 0.002
    penalty: float | None = None
    min_size: int = 1
    smooth_bins: int = 5
    significance: float = 3.0


def median_filter(values: np.ndarray, width: int) -> np.ndarray:
    """Running median of ``values`` (shape (n,)) over ``width`` samples.

    Windows are truncated at the ends (not padded with the end value, which would keep an
    impulse in the first or last bin alive).
    """
    if width <= 1 or len(values) < 3:
        return values
    width = width + 1 - width % 2  # odd
    half = width // 2
    n = len(values)
    out = np.empty(n, dtype=np.float64)
    if n >= width:  # full windows: the middle of each sorted window
        windows = np.lib.stride_tricks.sliding_window_view(values, width)
        out[half:n - half] = np.sort(windows, axis=1)[:, half]
    for i in (*range(min(half, n)), *range(max(n - half, half), n)):
        out[i] = median(values[max(0, i - half):i + half + 1])
    return out


def median(values: np.ndarray) -> float:
    """The median of ``values`` (shape (n,), n >= 1, no NaN): the middle value, or the mean of
    the two middle ones, as ``np.median`` computes it (without the import of ``numpy.ma`` that
    ``np.median`` costs)."""
    s = np.sort(np.asarray(values, dtype=np.float64))
    k = len(s) // 2
    return float(s[k]) if len(s) % 2 else float((s[k - 1] + s[k]) / 2.0)


@dataclass(frozen=True)
class ChangePoints:
    """Change points of one series.

    Attributes:
        times_s: change point times, ascending [s]: the first bin of each new segment.
        indices: (k,) index into the series of each new segment's first bin.
        penalty: the penalty used.
        noise_std: the series' noise estimate the penalty derives from (the larger of the
            baseline's standard deviation and that of the bin-to-bin differences over sqrt 2)
            [MDR units].
    """

    times_s: tuple[float, ...]
    indices: tuple[int, ...]
    penalty: float
    noise_std: float
    rises: tuple[bool, ...] | None = None

    def _first(self) -> int | None:
        """Position (in :attr:`times_s`) of the first rising change point."""
        if self.rises is None:
            return 0 if self.times_s else None
        return next((i for i, up in enumerate(self.rises) if up), None)

    @property
    def first_s(self) -> float | None:
        """t* of the channel: its first *rising* change point (the runs move apart), or None
        if they never did. A fall (the runs moving closer: a convergence) is no departure."""
        i = self._first()
        return None if i is None else self.times_s[i]

    @property
    def first_index(self) -> int | None:
        """Series index of the bin at :attr:`first_s` (None without it)."""
        i = self._first()
        return None if i is None else self.indices[i]

    @property
    def converges_s(self) -> tuple[float, ...]:
        """Times of the falling change points before :attr:`first_s` (all of them without
        it) [s]: the two runs drew closer there."""
        if self.rises is None:
            return ()
        first = self._first()
        stop = len(self.times_s) if first is None else first
        return tuple(t for t, up in zip(self.times_s[:stop], self.rises[:stop], strict=True)
                     if not up)


def penalty_for(values: np.ndarray, times_s: np.ndarray, cfg: ChangePointConfig) -> tuple[
    float, float
]:
    """(penalty, noise std) for a series, per the module docstring."""
    base = values[times_s < times_s[0] + cfg.baseline_s] if len(values) else values
    base_var = float(np.var(base)) if len(base) > 1 else 0.0
    diff_var = float(np.var(np.diff(values))) / 2.0 if len(values) > 2 else 0.0
    std = math.sqrt(max(base_var, diff_var))
    if cfg.penalty is not None:
        return float(cfg.penalty), std
    var = max(std, cfg.noise_floor) ** 2
    return cfg.penalty_scale * var * math.log(max(len(values), 2)), std


def detect(values: np.ndarray, times_s: np.ndarray, cfg: ChangePointConfig) -> ChangePoints:
    """Detect the change points of ``values`` (shape (n,)) sampled at ``times_s`` (shape (n,))."""
    raw = np.asarray(values, dtype=np.float64)
    times_s = np.asarray(times_s, dtype=np.float64)
    penalty, std = penalty_for(raw, times_s, cfg)  # noise of the raw series, impulses included
    values = median_filter(raw, cfg.smooth_bins)
    if len(values) < 2 * cfg.min_size or np.all(values == values[0]):
        return ChangePoints((), (), penalty, std)
    ends = pelt_l2(values, penalty, cfg.min_size)
    idx = _onsets(raw, values, [int(e) for e in ends[:-1]], cfg.smooth_bins // 2)  # last end: len
    idx = _significant(raw, values, idx, cfg.significance)
    return ChangePoints(tuple(float(times_s[i]) for i in idx), idx, penalty, std,
                        _rises(raw, values, idx))


def pelt_l2(values: np.ndarray, penalty: float, min_size: int = 1) -> list[int]:
    """Exact PELT for the l2 cost: the segmentation of ``values`` (shape (n,)) that minimises
    the sum of squared deviations from each segment's mean plus ``penalty`` per segment.

    Args:
        values: (n,) the series.
        penalty: cost of one more segment (> 0) [squared units of ``values``].
        min_size: fewest samples in a segment (>= 1).

    Returns:
        The end index (exclusive) of every segment, ascending; the last is ``n``
        (ruptures' ``predict`` convention).
    """
    x = np.ascontiguousarray(values, dtype=np.float64).reshape(-1)
    n = len(x)
    if n == 0:
        return []
    # cost of y[s:t] = (D[t] - D[s]) - S[s] / (t - s), with D the running sum of squares and
    # S[s] (updated as t grows) the sum of y_i * y_j over s <= i, j < t
    sum_sq = np.zeros(n + 1)
    sum_sq[1:] = np.cumsum(x * x)
    cross = np.zeros(n + 1)
    best = np.zeros(n + 1)  # best[t]: least penalised cost of y[:t]
    last_start = np.zeros(n + 1, dtype=np.int64)  # where the last segment of that starts
    bound = np.zeros(n + 1)  # best[s] + cost(y[s:t]) at the last t that evaluated s
    starts = np.arange(n + 1)
    s_min = 0  # admissible starts are s_min and (min_size..t - min_size) above it
    for t in range(1, min(2 * min_size, n + 1)):  # too short for a change point
        xt = x[t - 1]
        cross[t - 1::-1][:t] += 2.0 * np.cumsum(x[t - 1::-1] * xt) - xt * xt
        best[t] = (sum_sq[t] - sum_sq[0] - cross[0] / t) + penalty
    for t in range(2 * min_size, n + 1):
        xt = x[t - 1]
        cross[s_min:t] += (2.0 * np.cumsum(x[s_min:t][::-1] * xt) - xt * xt)[::-1]
        first = best[s_min] + (sum_sq[t] - sum_sq[s_min] - cross[s_min] / (t - s_min))
        bound[s_min] = first
        value, arg = first + penalty, s_min
        lo, hi = max(s_min + 1, min_size), t - min_size + 1
        if hi > lo:
            total = best[lo:hi] + ((sum_sq[t] - sum_sq[lo:hi]) - cross[lo:hi] / (t - starts[lo:hi]))
            bound[lo:hi] = total
            total += penalty
            k = int(np.argmin(total))  # the earliest start among equal costs
            if value > total[k]:
                value, arg = float(total[k]), lo + k
        best[t], last_start[t] = value, arg
        while bound[s_min] >= value and s_min < t - min_size + 1:  # pruning
            s_min += min_size if s_min == 0 else 1
    ends = []
    end = n
    while end > 0:
        ends.append(end)
        end = int(last_start[end])
    return ends[::-1]


def _onsets(raw: np.ndarray, smooth: np.ndarray, ends: list[int], reach: int) -> tuple[int, ...]:
    """Each change point moved back to the onset of its change (see the module docstring).

    Args:
        raw: (n,) the series; smooth: (n,) after the running median; ends: change point indices
        (ascending); reach: most bins a change point moves.
    """
    out: list[int] = []
    for i, k in enumerate(ends):
        start = out[-1] if out else 0
        stop = ends[i + 1] if i + 1 < len(ends) else len(raw)
        before, after = raw[start:max(start + 1, k - reach)], smooth[k:stop]
        level, new = median(before), median(after)
        tol = 3.0 * float(np.std(before)) + 1e-12
        sign = 1.0 if new > level else -1.0
        j = k
        while j - 1 > start and k - (j - 1) <= reach and sign * (raw[j - 1] - level) > tol \
                and sign * (raw[j - 1] - new) <= tol:
            j -= 1
        out.append(j)
    return tuple(out)


def _rises(raw: np.ndarray, smooth: np.ndarray, idx: tuple[int, ...]) -> tuple[bool, ...]:
    """Whether each change point raises the level (the runs move apart) or lowers it (they
    draw closer: a convergence, which Algorithm 1 does not time). The level before is the
    median of the raw values since the previous change point, the level after the median of
    the smoothed values up to the next one (as :func:`_significant` judges them).
    """
    out: list[bool] = []
    for i, k in enumerate(idx):
        start = idx[i - 1] if i else 0
        stop = idx[i + 1] if i + 1 < len(idx) else len(raw)
        before = raw[start:k] if k > start else raw[k:k + 1]
        out.append(median(smooth[k:stop]) >= median(before))
    return tuple(out)


def _significant(raw: np.ndarray, smooth: np.ndarray, idx: tuple[int, ...],
                 significance: float) -> tuple[int, ...]:
    """The change points whose new level stands out of the noise before them (module docstring).

    Args:
        raw: (n,) the series; smooth: (n,) after the running median; idx: change point
        indices (ascending).
    """
    if significance <= 0:
        return idx
    kept: list[int] = []
    for i, k in enumerate(idx):
        start = kept[-1] if kept else 0
        stop = idx[i + 1] if i + 1 < len(idx) else len(raw)
        before, after = raw[start:k], smooth[k:stop]
        if len(before) < 2 or len(after) == 0:
            kept.append(k)
            continue
        shift = abs(median(after) - median(before))
        if shift > significance * float(np.std(before)) + 1e-12:
            kept.append(k)
    return tuple(kept)
