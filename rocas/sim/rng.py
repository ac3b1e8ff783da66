"""Counter-based random numbers: a value depends only on (seed, tick, stream, index).

This is what makes a variant's run independent of the batch it is simulated in: no generator
state is shared between variants, and no draw depends on how many other draws happened.
"""

from __future__ import annotations

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
    count = int(np.prod(shape)) if shape else 1
    counter = np.arange(count, dtype=np.uint64) + np.uint64(
        (tick * 1_000_003 + stream * 7_919_993) % (1 << 62))
    with np.errstate(over="ignore"):
        z = _mix(seeds.astype(np.uint64)[:, None] * _GOLD + counter[None, :] * _GOLD)
    u = ((z >> _S11).astype(np.float64) + 0.5) * (1.0 / 9007199254740992.0)
    return u.reshape((seeds.shape[0], *shape))


def normal(seeds: np.ndarray, tick: int, stream: int, shape: tuple[int, ...]) -> np.ndarray:
    """Standard normal numbers, shape ``(N, *shape)`` (Box-Muller over two uniform streams)."""
    u = uniform(seeds, tick, stream, (2, *shape))
    return np.sqrt(-2.0 * numerics.log(u[:, 0])) * np.cos(2.0 * np.pi * u[:, 1])
