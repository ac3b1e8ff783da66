"""A fixed-seed slice of tests/benchmarks/bench_damage.py: structurally damaged catalog
recordings are refused or answered with a warning, never silently with a changed answer."""

from __future__ import annotations

from pathlib import Path

import pytest
from fuzz.structural import (
    KINDS,
    SILENT_CHANGED,
    case,
    classify,
    reconstruction,
    run_cmg,
    run_diff,
)

from rocas.catalog import entries
from rocas.rollout import simulate

RECORDINGS = Path(__file__).resolve().parents[2] / "recordings"

INPUTS = 24  # four of each kind


@pytest.fixture(scope="module")
def pair(tmp_path_factory):
    e = next(e for e in entries() if e.key.startswith("a10"))  # the shortest run
    ref = tmp_path_factory.mktemp("damage") / "reference.mcap"
    simulate(e.reference_scenario, output=ref)
    acc = RECORDINGS / f"{e.key}.mcap"
    return acc, ref, {"diff": run_diff(acc, ref), "cmg": run_cmg(acc),
                      "reconstruction": reconstruction(acc)}


def test_no_damaged_input_gets_a_silent_changed_answer(pair, tmp_path):
    acc, ref, base = pair
    seeds = [acc.read_bytes()]
    path = tmp_path / "in.mcap"
    silent, kinds = [], set()
    for number in range(INPUTS):
        _, kind, data, what = case(seeds, number)
        kinds.add(kind)
        path.write_bytes(data)
        got = run_diff(path, ref)
        outcome = {"diff": classify(got, base["diff"], got.answer != base["diff"].answer)}
        got = run_cmg(path)
        outcome["cmg"] = classify(got, base["cmg"], got.answer != base["cmg"].answer)
        got = reconstruction(path)
        b = base["reconstruction"]
        changed = not got.refused and got.answer[0] != b.answer[0]
        outcome["reconstruction"] = classify(got, b, changed)
        silent += [f"input {number} ({what}): {c}" for c, o in outcome.items()
                   if o == SILENT_CHANGED]
    assert kinds == set(KINDS)
    assert not silent, "\n".join(silent)
