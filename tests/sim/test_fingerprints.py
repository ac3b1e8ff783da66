"""The simulator's output is bit-identical on every machine.

Each catalog scenario's fingerprint (rocas.rollout.fingerprint: trajectories, oracle outcomes,
module output digests and, for the accidents, every published message) is stored in
fingerprints.json. A change of arithmetic that moves any bit fails here; regenerate with
``python tests/sim/test_fingerprints.py --update`` and regenerate the shipped recordings
(``rocas catalog record recordings/``) in the same commit, saying why.

The subprocess tests run the simulator under two explicitly set OpenBLAS kernels and under
numpy's narrower SIMD paths (``NPY_DISABLE_CPU_FEATURES``), and compare fingerprints.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

from rocas.catalog import entries
from rocas.rollout.fingerprint import run_fingerprint

STORED = Path(__file__).with_name("fingerprints.json")
ENTRIES = {e.id: e for e in entries()}


def compute_all() -> dict[str, str]:
    out = {}
    for e in ENTRIES.values():
        out[e.scenario.name] = run_fingerprint(e.scenario)
        out[e.reference_scenario.name] = run_fingerprint(e.reference_scenario, with_messages=False)
    return out


@pytest.mark.parametrize("type_id", list(ENTRIES))
def test_catalog_fingerprints_match_the_stored_ones(type_id):
    stored = json.loads(STORED.read_text())
    e = ENTRIES[type_id]
    assert run_fingerprint(e.scenario) == stored[e.scenario.name]
    assert run_fingerprint(e.reference_scenario, with_messages=False) \
        == stored[e.reference_scenario.name]


_CHILD = """
import json, sys
from rocas.catalog import entry
from rocas.rollout.fingerprint import run_fingerprint
print(json.dumps([run_fingerprint(entry(t).scenario) for t in sys.argv[1:]]))
"""

# A9 and A2 went wrong first under another kernel (the brake classifier's matmul); A4 and A8
# depended on numpy's SIMD path (argpartition ties, exp/arctan2 kernels)
_PROBES = ("A9", "A2", "A4", "A8")


def _fingerprints_in_child(**env: str) -> list[str]:
    full = dict(os.environ, **env)
    done = subprocess.run([sys.executable, "-c", _CHILD, *_PROBES], env=full, capture_output=True,
                          text=True, timeout=300, check=False)
    assert done.returncode == 0, done.stderr[-2000:]
    return json.loads(done.stdout)


@pytest.mark.slow
def test_the_same_bits_under_two_openblas_kernels():
    stored = json.loads(STORED.read_text())
    expected = [stored[ENTRIES[t].scenario.name] for t in _PROBES]
    assert _fingerprints_in_child(OPENBLAS_CORETYPE="Haswell") == expected
    assert _fingerprints_in_child(OPENBLAS_CORETYPE="Prescott") == expected


@pytest.mark.slow
def test_the_same_bits_on_narrower_simd_paths():
    import numpy as np

    # "X86_V2 X86_V3* X86_V4* AVX512_ICL*": the starred paths are dispatched on this CPU
    info = np.lib._utils_impl._opt_info()
    dispatched = [tok.rstrip("*") for tok in info.split() if tok.endswith("*")]
    if not dispatched:
        pytest.skip(f"numpy dispatches to no SIMD path above its baseline here ({info})")
    stored = json.loads(STORED.read_text())
    expected = [stored[ENTRIES[t].scenario.name] for t in _PROBES]
    assert _fingerprints_in_child(NPY_DISABLE_CPU_FEATURES=" ".join(dispatched)) == expected


if __name__ == "__main__":
    if sys.argv[1:] != ["--update"]:
        sys.exit("usage: python tests/sim/test_fingerprints.py --update")
    STORED.write_text(json.dumps(compute_all(), indent=1, sort_keys=True) + "\n")
    print(f"wrote {STORED}")
