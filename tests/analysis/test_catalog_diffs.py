"""Every catalog entry's documented ``diff_module``: rocas diff between the shipped accident
recording and the entry's reference execution names that module, and the module's first output
channel departs at the documented ``diff_change_s``."""

from __future__ import annotations

from pathlib import Path

import pytest

from rocas.analysis.diff import diff
from rocas.catalog import entries
from rocas.rollout import simulate

RECORDINGS = Path(__file__).resolve().parents[2] / "recordings"
ENTRIES = {e.id: e for e in entries()}


@pytest.mark.parametrize("type_id", list(ENTRIES))
def test_the_diff_names_the_documented_module(type_id, tmp_path):
    e = ENTRIES[type_id]
    reference = tmp_path / "reference.mcap"
    simulate(e.reference_scenario, output=reference)
    result = diff(RECORDINGS / f"{e.key}.mcap", reference)
    assert result.deviating_module == e.truth.diff_module
    written = [c.change_point_s for c in result.channels
               if e.truth.diff_module in c.writers and c.change_point_s is not None]
    assert min(written) == pytest.approx(e.truth.diff_change_s, abs=0.06)
