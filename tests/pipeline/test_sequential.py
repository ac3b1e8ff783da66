"""The regression test's sequential stop (rocas.pipeline.sequential) and phase V with it."""

import json
import math
import random
import shutil

import pytest

import rocas.pipeline.sequential as sequential
from rocas.pipeline import AnalyzeConfig
from rocas.pipeline import analyze as _analyze
from rocas.pipeline.sequential import looks, regression_test, sign_test
from rocas.scenarios import load_example
from rocas.search import SerialExecutor


def analyze(*args, **kwargs):
    """The analysis's report as its report.json object (the shape these tests read)."""
    return _analyze(*args, **kwargs).to_json()


def test_the_looks_come_every_look_variants_and_at_the_end():
    assert looks(200) == [50, 100, 150, 200]
    assert looks(120, 50) == [50, 100, 120]
    assert looks(12) == [12]
    assert looks(0) == []


def test_the_sign_test_is_the_exact_binomial_tail():
    assert sign_test(0, 0) == 1.0
    assert sign_test(10, 0) == 0.5 ** 10
    assert sign_test(0, 10) == 1.0
    # P(X >= 8), X ~ Binomial(10, 1/2) = (45 + 10 + 1) / 1024
    assert math.isclose(sign_test(8, 2), 56 / 1024)


def test_the_test_stops_when_the_fix_is_clearly_better_and_only_at_a_look():
    orig = [False] * 50
    fixed = [True] * 12 + [False] * 38 + [True] * 150
    t = regression_test(orig, fixed, 200)
    assert t["decision"] == "fix_better" and t["stopped_early"]
    assert (t["fix_only"], t["original_only"]) == (12, 0)
    assert t["alpha_per_look"] == 0.01 / 8
    # the same discordance after 49 variants is no look: the level was split over the looks
    assert regression_test(orig[:49], fixed, 200)["decision"] is None
    # each look and direction is held to 0.01 / 8 = 1/800: 10 of 10 one way (p = 1/1024) is enough ...
    assert regression_test([False] * 50, [True] * 10 + [False] * 190, 200)["decision"] == "fix_better"
    # ... and 9 of 9 is not (p = 1/512)
    assert regression_test([False] * 50, [True] * 9 + [False] * 191, 200)["decision"] is None


def test_the_test_stops_when_the_fix_is_clearly_worse():
    t = regression_test([True] * 50, [False] * 20 + [True] * 180, 200)
    assert t["decision"] == "fix_worse" and t["stopped_early"]


def test_a_decision_at_the_last_look_is_no_early_stop():
    t = regression_test([False] * 200, [True] * 200, 200)
    assert t["decision"] == "fix_better" and not t["stopped_early"]


def test_without_a_difference_it_rarely_stops_in_either_direction():
    # both configurations avoid the accident with the same chance, independently per variant:
    # the test may stop (wrongly) in at most REGRESSION_ALPHA of the runs
    rng = random.Random(3)
    stops = 0
    runs = 2000
    for _ in range(runs):
        orig = [rng.random() < 0.5 for _ in range(200)]
        fixed = [rng.random() < 0.5 for _ in range(200)]
        for m in looks(200):
            t = regression_test(orig[:m], fixed, 200)
            if t["decision"] is not None:
                stops += 1
                break
    assert stops / runs <= sequential.REGRESSION_ALPHA


@pytest.mark.slow
def test_an_early_stopped_validation_gives_the_verdict_of_the_whole_one(tmp_path, monkeypatch):
    red_truck = load_example("roundabout_red_truck")
    cfg = AnalyzeConfig(seed=0, budget=16, population=8, validation_variants=40, batch_size=64,
                        alternate_references=0, second_opinion=False)
    out = tmp_path / "run"

    def stop_before_validation(phase, info):
        if phase == "answer":
            raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        analyze(red_truck, out, cfg, executor=SerialExecutor(), progress=stop_before_validation)
    whole_dir = tmp_path / "whole"
    shutil.copytree(out, whole_dir)
    monkeypatch.setattr(sequential, "REGRESSION_LOOK", 10)
    early = analyze(red_truck, out, cfg, executor=SerialExecutor(), resume=True)
    monkeypatch.setattr(sequential, "REGRESSION_ALPHA", 0.0)  # never separated: every variant
    whole = analyze(red_truck, whole_dir, cfg, executor=SerialExecutor(), resume=True)

    ve, vw = early["validation"], whole["validation"]
    assert ve["regression_test"]["stopped_early"] and ve["regression_test"]["decision"] == "fix_better"
    assert ve["original_variants"] < 40 == vw["original_variants"]
    assert not vw["regression_test"]["stopped_early"]
    assert ve["simulations"] == vw["simulations"] - (40 - ve["original_variants"])
    # the same verdict: the fix is not worse, the same rates where both ran, the same robust value
    assert ve["fix_makes_it_worse"] is vw["fix_makes_it_worse"] is False
    assert ve["success_rate_fixed"] == vw["success_rate_fixed"]
    assert ve["success_rate_original"] == vw["success_rate_original"] == 0.0
    assert ve["stronger"] == vw["stronger"] and ve["robust_fix"] == vw["robust_fix"]
    assert {k: v for k, v in early.items() if k not in ("validation", "timings_s", "evaluations")} \
        == {k: v for k, v in whole.items() if k not in ("validation", "timings_s", "evaluations")}
    # and the report says so
    md = (out / "report.md").read_text()
    assert f"stopped after {ve['original_variants']} of 40 variants" in md
    assert json.loads((out / "validation.json").read_text()) == ve
