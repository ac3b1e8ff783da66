"""The README's and docs/viewer.md's pictures are the current code's (issue 40).

``docs/images/make_screenshots.py`` writes each picture with its facts beside it
(``NAME.json``: the command, what the picture shows, the picture's SHA-256). A picture replaced
by hand fails here (its digest), and so does one whose facts the code no longer gives: the fast
tests hold the facts against the README's printed report (which the slow quick-start test holds
against a real run), the slow ones against a fresh analysis and a fresh triage.
"""

import importlib.util
import json
import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
IMAGES = ROOT / "docs" / "images"


def _script():
    spec = importlib.util.spec_from_file_location("make_screenshots", IMAGES / "make_screenshots.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def _sidecar(name: str) -> dict:
    return json.loads((IMAGES / f"{name}.json").read_text(encoding="utf-8"))


@pytest.mark.parametrize("name", ["rerun-view", "triage-view"])
def test_each_picture_is_the_one_its_script_wrote(name):
    side = _sidecar(name)
    assert side["made_by"] == "python docs/images/make_screenshots.py"
    assert _script().sha256(IMAGES / f"{name}.png") == side["png_sha256"], (
        f"docs/images/{name}.png is not the picture make_screenshots.py wrote; run it again")


def _readme_report_row(label: str) -> str:
    text = (ROOT / "README.md").read_text(encoding="utf-8")
    block = text.split("Then the report", 1)[1].split("```", 2)[1]
    row = next(ln for ln in block.splitlines() if ln.startswith(f" {label} "))
    return re.sub(r"\s+", " ", row[len(label) + 1:]).strip()


def test_the_analysis_picture_shows_the_readmes_report():
    facts = _sidecar("rerun-view")["facts"]
    assert _sidecar("rerun-view")["command"] == "rocas analyze recordings/a09_red_truck_roundabout.mcap"
    assert facts["verdict"] == _readme_report_row("verdict")
    assert facts["triggering_entity"] == _readme_report_row("triggering entity")
    assert _readme_report_row("deviating module").startswith(f"{facts['deviating_module']} walk:")
    assert facts["misconfiguration"] == [_readme_report_row("misconfiguration")]


def test_the_triage_picture_is_a_campaign_of_shipped_recordings():
    script = _script()
    facts = _sidecar("triage-view")["facts"]
    assert facts["accidents"] == sorted(script.CAMPAIGN)
    assert all((ROOT / "recordings" / f"{n}.mcap").is_file() for n in facts["accidents"])
    assert facts["failed"] == [] and sum(g["count"] for g in facts["groups"]) == len(script.CAMPAIGN)


@pytest.mark.slow  # one analysis of A9, about 10 s of CPU
def test_the_analysis_pictures_facts_are_the_current_codes(tmp_path):
    from rocas.pipeline.analyze import analyze
    from rocas.pipeline.config import AnalyzeConfig

    report = analyze(ROOT / "recordings" / "a09_red_truck_roundabout.mcap", tmp_path / "run",
                     AnalyzeConfig())
    assert _script().report_facts(report.to_json()) == _sidecar("rerun-view")["facts"]


@pytest.mark.slow  # a triage of three shipped accidents, about 30 s of CPU
def test_the_triage_pictures_facts_are_the_current_codes(tmp_path):
    from rocas.campaign import collect_inputs, triage
    from rocas.pipeline.config import AnalyzeConfig

    script = _script()
    inputs = collect_inputs([str(ROOT / "recordings" / f"{n}.mcap") for n in script.CAMPAIGN])
    campaign = triage(inputs, tmp_path / "campaign", AnalyzeConfig(validation_variants=0))
    assert script.campaign_facts(campaign) == _sidecar("triage-view")["facts"]
