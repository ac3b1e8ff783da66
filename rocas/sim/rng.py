"""Counter-based random numbers: a value depends only on (seed, tick, stream, index).

This is what makes a variant's run independent of the batch it is simulated in: no generator
state is shared between variants, and no draw depends on how many other draws happened.
"""

from __future__ import annotations

import math

import numpy as np

from rocas import numerics

_M1 = np.uint64(0xBF58476D1CE4E5B9)
_M2 = np.uint64(0x94D049BB133111EB)
_GOLD = np.uint64(0x9E3779B97F4A7C15)
_S30 = np.uint64(30)
_S27 = np.uint64(27)
_S31 = np.uint64(31)
_S11 = np.uint64(11)


def _mix(z: np.ndarray) -> np.ndarray:
    z = (z ^ (z >> _S30)) * _M1
    z = (z ^ (z >> _S27)) * _M2
    return z ^ (z >> _S31)


def uniform(seeds: np.ndarray, tick: int, stream: int, shape: tuple[int, ...]) -> np.ndarray:
    """Uniform numbers in (0, 1), shape ``(N, *shape)``; ``seeds`` has shape (N,) uint64."""
    count = math.prod(shape)
    counter = _counters(count) + np.uint64((tick * 1_000_003 + stream * 7_919_993) % (1 << 62))
    if seeds.dtype != np.uint64:
        seeds = seeds.astype(np.uint64)
    # unsigned array arithmetic wraps modulo 2**64 and never warns (only numpy scalars do)
    z = _mix(seeds[:, None] * _GOLD + counter * _GOLD)
    u = ((z >> _S11).astype(np.float64) + 0.5) * (1.0 / 9007199254740992.0)
    return u.reshape((seeds.shape[0], *shape))


_COUNTERS: dict[int, np.ndarray] = {}


def _counters(count: int) -> np.ndarray:
    """``np.arange(count, dtype=uint64)``, made once per count (read-only: callers add to it)."""
    out = _COUNTERS.get(count)
    if out is None:
        out = np.arange(count, dtype=np.uint64)
        out.flags.writeable = False
        _COUNTERS[count] = out
    return out


def normal(seeds: np.ndarray, tick: int, stream: int, shape: tuple[int, ...]) -> np.ndarray:
    """Standard normal numbers, shape ``(N, *shape)`` (Box-Muller over two uniform streams)."""
    u = uniform(seeds, tick, stream, (2, *shape))
    # uniform's numbers lie in (0, 1): log needs none of its special cases
    return np.sqrt(-2.0 * numerics.log_positive(u[:, 0])) * np.cos(2.0 * np.pi * u[:, 1])
