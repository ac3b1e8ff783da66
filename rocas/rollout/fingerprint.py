"""A run's fingerprint: one sha256 over everything a simulation with the built-in ADS produces.

Used to prove that the simulator's output is bit-identical across machines, BLAS kernels and
SIMD paths (tests/sim/test_fingerprints.py stores the catalog's fingerprints).
"""

from __future__ import annotations

import hashlib
import tempfile
from pathlib import Path

import numpy as np

from rocas.scenarios.model import Scenario


def run_fingerprint(scenario: Scenario, *, with_messages: bool = True) -> str:
    """sha256 (hex) of ``scenario``'s trajectories, gaps, per-module output digests and, with
    ``with_messages``, the payload of every message the run publishes, in log order."""
    from mcap.reader import make_reader

    from rocas.rollout import simulate, simulate_batch

    h = hashlib.sha256()
    res = simulate_batch(scenario, track_outputs=True)
    for a in (res.ego, res.actors, res.min_gap, res.digests):
        h.update(np.ascontiguousarray(a, dtype=np.float64).tobytes())
    h.update(repr(res.outcomes).encode())
    if with_messages:
        with tempfile.TemporaryDirectory() as tmp:
            path = Path(tmp) / "run.mcap"
            simulate(scenario, output=path)
            with open(path, "rb") as f:
                for _, channel, message in make_reader(f).iter_messages(log_time_order=True):
                    h.update(channel.topic.encode())
                    h.update(message.log_time.to_bytes(8, "little"))
                    h.update(message.data)
    return h.hexdigest()
