"""The report is one view model rendered three ways, and report.json keeps its bytes: the
fixtures in data/ were written by rocas before the phase results were typed (report.json,
report.md, and the terminal view of ``rocas analyze``) for catalog entries A1, A6 (the walk
went on past a module substitution cleared, then the fix was found in the module reading
the walk's: a06_validated, with the default 200 variants, also a sequential stop and a robust
value), A7 (no configuration fix), A9 (the walk passed
over entries) and the roundabout example at small budgets."""

from __future__ import annotations

import io
import json
from pathlib import Path

import pytest

from rocas.cli.analyze import render
from rocas.cli.console import Env
from rocas.pipeline.codec import ShapeError
from rocas.pipeline.report import Report, markdown
from rocas.pipeline.results import (
    DiffPhaseResult,
    ModuleRevision,
    current_answer,
)

DATA = Path(__file__).parent / "data"
FIXTURES = sorted(p.name for p in DATA.iterdir() if (p / "report.json").is_file())


@pytest.fixture(params=FIXTURES)
def stored(request):
    return DATA / request.param


def test_report_json_reads_and_writes_back_byte_for_byte(stored):
    text = (stored / "report.json").read_text()
    report = Report.from_json(json.loads(text))
    assert json.dumps(report.to_json(), indent=2) == text


def test_report_md_and_the_terminal_view_render_as_before(stored):
    report = Report.from_json(json.loads((stored / "report.json").read_text()))
    assert markdown(report) == (stored / "report.md").read_text()
    out = io.StringIO()
    render(report, Path("runs/x"), Env(stdout=out, stderr=io.StringIO()))
    assert out.getvalue() == (stored / "terminal.txt").read_text()


def test_a_report_of_another_shape_is_refused():
    data = json.loads((DATA / FIXTURES[0] / "report.json").read_text())
    with pytest.raises(ShapeError, match="deviating_module"):
        Report.from_json({**data, "deviating_module": 3})
    with pytest.raises(ShapeError, match="unknown key 'extra'"):
        Report.from_json({**data, "extra": 1})


DIFF = DiffPhaseResult(deviating_module="perception", path=("/control", "control", "/perception",
                                                            "perception"),
                       control_channel="/control", fallback=None, entries=None, warnings=("w",))


def test_the_current_answer_applies_the_revisions_in_order():
    walked = ModuleRevision(by="confidence", reason="walk_passed", before="perception",
                            after="planning", path=("/control", "control", "/planning", "planning"),
                            fallback=None, cleared_passed=("perception",))
    adopted = ModuleRevision(by="confidence", reason="adopted_reference", before="planning",
                             after="prediction", path=("/control", "control", "/prediction",
                                                       "prediction"),
                             fallback="no change point", reference="reference_2.mcap",
                             control_channel="/control", entries=None, warnings=())
    suspect = ModuleRevision(by="cyber", reason="second_suspect", before="prediction",
                             after="planning", path=(), reads_named=True)
    assert current_answer(DIFF).deviating_module == "perception"
    one = current_answer(DIFF, [walked])
    assert (one.deviating_module, one.cleared_passed, one.warnings) == ("planning", ("perception",), ("w",))
    two = current_answer(DIFF, [walked, adopted])
    assert two.deviating_module == "prediction" and two.cleared_passed is None
    assert two.adopted_from == "reference_2.mcap" and two.fallback == "no change point"
    three = current_answer(DIFF, [walked, adopted, suspect])
    assert (three.deviating_module, three.path, three.walk_named, three.suspect_reads_named) == (
        "planning", (), "prediction", True)
    assert three.fallback == "no change point" and three.adopted_from == "reference_2.mcap"
    assert DIFF.deviating_module == "perception"  # frozen: nothing was rewritten


def test_a_revision_round_trips_through_json():
    rev = ModuleRevision(by="confidence", reason="walk_passed", before="a", after="b", path=("x",),
                         entries_passed={"/t": 1.5})
    assert ModuleRevision.from_json(json.loads(json.dumps(rev.to_json()))) == rev


def test_a_revision_for_an_unknown_reason_is_a_shape_error():
    with pytest.raises(ShapeError, match="reason is not one of"):
        ModuleRevision.from_json({"by": "cyber", "reason": "hunch", "before": "a", "after": "b",
                                  "path": []})
