"""Every shipped catalog recording replays from the recording alone and reproduces its accident;
for fixable entries the documented fix, replayed as a what-if, avoids it."""

from pathlib import Path

import pytest

from rocas.replay import replay
from rocas.scenarios.catalog import entries

RECORDINGS = Path(__file__).resolve().parents[2] / "recordings"
ENTRIES = {e.id: e for e in entries()}


@pytest.mark.parametrize("type_id", list(ENTRIES))
def test_the_shipped_recording_replays_and_reproduces(type_id):
    e = ENTRIES[type_id]
    report = replay(RECORDINGS / f"{e.key}.mcap")
    assert report.reproduced, report.to_dict()
    assert report.accident.kind == e.truth.consequence
    assert report.ego_rmse_m < 0.5
    for fix in e.truth.fixes:
        what_if = replay(RECORDINGS / f"{e.key}.mcap", dict(fix))
        assert what_if.accident is None, (fix, what_if.to_dict())
