"""rocas diff on a catalog pair with ordinary logging artefacts on one side: the fast subset of
tests/benchmarks/bench_artefacts.py (the A9 pair of tests/data/pairs, truth: perception; the
artefacts of tests/artefacts.py). On the code before issue 36's pairing (82438f2), 5 of these 12
named another module without a warning and 2 were refused as unrelated runs."""

from __future__ import annotations

import json
from pathlib import Path

import artefacts as A
import pytest

ROOT = Path(__file__).resolve().parents[2]
PAIRS = {p["name"]: p for p in json.loads((ROOT / "tests/data/pairs/pairs.json").read_text())["pairs"]}
PAIR = PAIRS["a09"]

CASES = {
    "truncate_end[1.5s]@reference": ("reference", A.truncate_end(1.5)),
    "late_start[1s]@reference": ("reference", A.late_start(1.0)),
    "latched_early[1s]@accident": ("accident", A.latched_early(None, 1.0)),
    "duplicate@reference": ("reference", A.duplicate(seed=0)),
    "lose_1%@accident": ("accident", A.lose(0.01, seed=0)),
    "lose_1%@reference": ("reference", A.lose(0.01, seed=1)),
    "half_rate[deviating]@reference": ("reference", A.half_rate(PAIR["deviating_topic"])),
    "half_rate[other]@accident": ("accident", A.half_rate(PAIR["other_topic"])),
    "clock+0.5s[deviating]@reference": ("reference", A.clock_offset(PAIR["deviating_topic"], 0.5)),
    "flush_1s[deviating]@reference": ("reference", A.flush_stamps(PAIR["deviating_topic"], 1.0)),
    "flush_1s[other]@accident": ("accident", A.flush_stamps(PAIR["other_topic"], 1.0)),
    "jitter_20ms@reference": ("reference", A.jitter(20.0, seed=0)),
}


@pytest.mark.parametrize("name", list(CASES))
def test_an_artefact_on_one_side_leaves_the_answer(name, tmp_path):
    side, transform = CASES[name]
    acc, ref = ROOT / PAIR["accident"], ROOT / PAIR["reference"]
    changed = tmp_path / f"{side}.mcap"
    A.rewrite(acc if side == "accident" else ref, changed, transform)
    a, b = (acc, changed) if side == "reference" else (changed, ref)
    v = A.judge(a, b, PAIR["truth"])
    assert v.verdict == A.RIGHT, f"{name}: {v.verdict} ({v.detail}); {v.warnings}"
