"""Phase V beyond the paper's regression test: the fix moved further the same way, and the
robust value chosen from those stronger values."""

import dataclasses
import json

import pytest

from rocas.pipeline import AnalyzeConfig
from rocas.pipeline import analyze as _analyze
from rocas.pipeline.cyber import cyber_space
from rocas.pipeline.results import RobustFix, StrongerValue
from rocas.pipeline.validation import (
    ROBUST_TOLERANCE,
    STRONGER_FRACTIONS,
    _robust,
    stronger_fixes,
    sweep_settled,
    validation_simulations,
)
from rocas.scenarios import load_example
from rocas.search import SerialExecutor


def analyze(*args, **kwargs):
    """The analysis's report as its report.json object (the shape these tests read)."""
    return _analyze(*args, **kwargs).to_json()


def test_stronger_values_go_on_the_way_the_fix_went_to_the_end_of_the_range():
    space = cyber_space("perception", {})
    # brake_threshold: 0.8 by default, range 0.05-0.99, the fix raised it; track_max_missed_frames
    # is an integer parameter (range 0-20, default 3), the fix raised it to 5
    out = stronger_fixes({"perception.brake_threshold": 0.85, "perception.track_max_missed_frames": 5.0},
                         space)
    assert [f for f, _ in out] == list(STRONGER_FRACTIONS)
    up = [v["perception.brake_threshold"] for _, v in out]
    assert up == pytest.approx([0.85 + f * (0.99 - 0.85) for f in STRONGER_FRACTIONS])
    assert up[-1] == pytest.approx(0.99)
    frames = [v["perception.track_max_missed_frames"] for _, v in out]
    assert frames == [7.0, 9.0, 12.0, 16.0, 20.0]  # 5 + f * 15, rounded
    # a fix that lowered a parameter (tl_facing_tolerance_deg 40 -> 30; range 5-90) goes on down
    (_, first), *_, (_, last) = stronger_fixes({"perception.tl_facing_tolerance_deg": 30.0}, space)
    assert first["perception.tl_facing_tolerance_deg"] == pytest.approx(30.0 - 0.125 * 25.0)
    assert last["perception.tl_facing_tolerance_deg"] == pytest.approx(5.0)


def test_stronger_values_stay_inside_the_range_despite_rounding():
    # 6.405920704482398 + 1.0 * (0.1 - 6.405920704482398) is 0.09999999999999964 in floating
    # point, which the ADS refuses as out of range [0.1, 10] (a generated A3 instance hit it)
    space = cyber_space("prediction", {"prediction.accel_decay_s": 8.0})  # the fix lowered it
    out = stronger_fixes({"prediction.accel_decay_s": 6.405920704482398}, space)
    var = space.variable("prediction.accel_decay_s")
    assert var.low == 0.1
    assert all(var.low <= v["prediction.accel_decay_s"] <= var.high for _, v in out)
    assert out[-1][1]["prediction.accel_decay_s"] == 0.1


def test_stronger_values_that_coincide_are_tried_once():
    space = cyber_space("perception", {})
    # a fix at the end of its range has nothing stronger to try
    assert stronger_fixes({"perception.brake_threshold": 0.99}, space) == []
    # brake_min_frames (integer, range 1-10, default 3) raised to 9: 9 + f * 1 rounds to 9, 9, 10,
    # 10, 10, so only the first 10 remains
    assert stronger_fixes({"perception.brake_min_frames": 9.0}, space) == [
        (0.5, {"perception.brake_min_frames": 10.0})]


def test_phase_v_simulation_count():
    assert validation_simulations(200) == 400 + len(STRONGER_FRACTIONS) * 201
    assert validation_simulations(0) == 0  # --validation 0: no regression test, no sweep


def _sweep(*rates, avoids=None, h1=None):
    return [StrongerValue(fraction=f, fix={"p": f}, success_rate=r,
                          avoids_accident=True if avoids is None else avoids[k],
                          h1_m2=0.0 if h1 is None else h1[k])
            for k, (f, r) in enumerate(zip(STRONGER_FRACTIONS, rates, strict=True))]


def test_the_robust_value_is_the_closest_within_the_tolerance_of_the_best():
    # best 1.0: the first value at 0.95 or above is the one (fraction 0.25), not the best itself
    rob = _robust(0.60, _sweep(0.835, 0.96, 1.0, 1.0, 1.0), h1_limit=1.0)
    assert rob == RobustFix(fix={"p": 0.25}, success_rate=0.96, fraction=0.25)


def test_no_robust_value_when_no_stronger_value_avoids_clearly_more():
    assert _robust(0.135, _sweep(0.14, 0.15, 0.155, 0.16, 0.135 + ROBUST_TOLERANCE - 0.01),
                   h1_limit=1.0) is None
    assert _robust(None, [], h1_limit=1.0) is None


def test_values_that_no_longer_avoid_the_accident_or_move_the_ego_earlier_do_not_count():
    rob = _robust(0.5, _sweep(0.9, 0.95, 1.0, 1.0, 1.0, avoids=[False, True, True, True, True],
                              h1=[0.0, 2.0, 0.5, 0.5, 0.5]), h1_limit=1.0)
    assert rob is not None and rob.fraction == 0.5


@pytest.mark.slow  # about 75 s
def test_an_interrupted_validation_resumes_after_its_last_finished_slice(tmp_path, monkeypatch):
    import shutil

    red_truck = load_example("roundabout_red_truck")
    cfg = AnalyzeConfig(seed=1, budget=16, population=8, validation_variants=12, batch_size=8)
    out = tmp_path / "run"
    counts = []

    def stop_in_validation(phase, info):
        if phase == "answer":  # said once, before phase V's first count
            counts.append(info)
        if phase == "validation":
            counts.append(info.get("evaluations"))
            if info.get("evaluations", 0) >= 13:
                raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        analyze(red_truck, out, cfg, executor=SerialExecutor(), progress=stop_in_validation)
    # slices of 8 of the first wave: the 5 stronger values on the accident, the minimal fix
    # on the 12 variants and the original on its first (and only) look of 12
    answer, *counts = counts
    assert answer["module"] == "perception" and answer["fix"].startswith("perception.")
    assert counts == [0, 8, 16]
    assert len(json.loads((out / "validation.ckpt").read_text())["accident"]) == 16

    # a checkpoint altered to steer the verdict (every flag flipped) is caught by running
    # some of its simulations again: damage, not a result
    from rocas.errors import InputError

    crafted = tmp_path / "crafted"
    shutil.copytree(out, crafted)
    ckpt = json.loads((crafted / "validation.ckpt").read_text())
    ckpt["accident"] = [not a for a in ckpt["accident"]]
    (crafted / "validation.ckpt").write_text(json.dumps(ckpt))
    with pytest.raises(InputError, match="validation.ckpt does not match the simulations"):
        analyze(red_truck, crafted, cfg, executor=SerialExecutor(), resume=True)

    # the same run without the interruption: phases I-IV as they were, the validation whole
    whole_dir = tmp_path / "whole"
    shutil.copytree(out, whole_dir)
    (whole_dir / "validation.ckpt").unlink()
    counts.clear()
    whole = analyze(red_truck, whole_dir, cfg, executor=SerialExecutor(), resume=True,
                    progress=lambda phase, info: counts.append(
                        (info.get("evaluations"), info.get("simulations"))) if phase == "validation"
                    else None)
    total = whole["evaluations"]["validation"]
    assert total == whole["validation"]["simulations"] <= validation_simulations(12) == 89
    assert counts[:4] == [(0, 89), (8, 89), (16, 89), (24, 89)]  # the bar advances slice by slice
    assert counts[-1] == (total, total)  # and ends at what was run

    # fixed.mcap is recorded by phase V as an extra row of its first batch: the file the fix's
    # run alone writes; a resumed run whose recording is missing records it again
    from rocas.rollout import simulate

    fix = json.loads((out / "cyber.json").read_text())["fix"]
    simulate(red_truck, fix, output=tmp_path / "fixed_alone.mcap")
    assert (out / "fixed.mcap").read_bytes() == (tmp_path / "fixed_alone.mcap").read_bytes()
    assert (whole_dir / "fixed.mcap").read_bytes() == (tmp_path / "fixed_alone.mcap").read_bytes()
    (out / "fixed.mcap").unlink()

    # resumed with other slices (the results do not depend on them), from the 17th simulation
    import rocas.pipeline.validation as validation

    monkeypatch.setattr(validation, "VALIDATION_SLICE_BATCHES", 2)  # slices of 16
    counts.clear()
    resumed = analyze(red_truck, out, cfg, executor=SerialExecutor(), resume=True,
                      progress=lambda phase, info: counts.append(info.get("evaluations"))
                      if phase == "validation" else None)
    assert counts[0] == 16 and counts[1] == 29  # the first wave's end: 16 + 13
    assert {k: v for k, v in resumed.items() if k not in ("timings_s", "settings")} == \
        {k: v for k, v in whole.items() if k not in ("timings_s", "settings")}
    assert json.loads((out / "validation.json").read_text()) == whole["validation"]
    assert not (out / "validation.ckpt").exists()
    assert (out / "fixed.mcap").read_bytes() == (tmp_path / "fixed_alone.mcap").read_bytes()


def _full_sweep_pick(fixed, rates):
    sweep = _sweep(*rates)
    return _robust(fixed, sweep, h1_limit=1.0)


def test_the_sweep_stops_only_when_the_rest_cannot_change_the_robust_value():
    import random

    rng = random.Random(5)
    grid = [k / 20 for k in range(21)]
    stopped = 0
    for _ in range(3000):
        fixed = rng.choice(grid)
        rates = [rng.choice(grid) for _ in STRONGER_FRACTIONS]
        if rng.random() < 0.5:
            rates.sort()  # stronger values tend to avoid more
        # what the phase runs: each value only while the sweep is not settled
        run = []
        for k in range(len(rates)):
            if sweep_settled(fixed, run):
                break
            run.append(rates[k])
        stopped += len(run) < len(rates)
        sweep = _sweep(*rates)
        sweep[len(run):] = [dataclasses.replace(e, success_rate=None) for e in sweep[len(run):]]
        assert _robust(fixed, sweep, h1_limit=1.0) == _full_sweep_pick(fixed, rates), (fixed, rates)
    assert stopped > 300  # the stop is not a dead letter (683 of 3000 here)


def test_the_sweep_is_settled_by_a_minimal_fix_that_cannot_be_beaten_by_the_tolerance():
    assert sweep_settled(0.97, [])  # nothing can be 0.05 better than 0.97
    assert not sweep_settled(0.90, [])
    # 0.96 is within 0.05 of any rate; 0.85 falls short of 0.96 by more: 0.25 is the robust one
    assert sweep_settled(0.625, [0.85, 0.96])
    assert not sweep_settled(0.625, [0.85, 0.93])  # a later 1.0 would rule out 0.93


def test_a_validation_checkpoint_is_checked_before_it_is_used(tmp_path):
    from rocas.errors import InputError
    from rocas.pipeline.validation import _validation_checkpoint

    path = tmp_path / "validation.ckpt"
    fix = {"perception.x": 1.0}
    ident = {"format": 4, "fix": fix, "variants": 2, "source_sha256": "abc", "seed": 1}

    def load(**content):
        path.write_text(json.dumps({**ident, "accident": [], "h1_m2": {}, **content}))
        return _validation_checkpoint(path, fix, 2, planned=9, source_sha256="abc", seed=1)

    assert load(accident=[True, False], h1_m2={"0": 0.5})["accident"] == [True, False]
    # of another input, seed or fix: not this validation's, so started afresh
    assert load(source_sha256="other", accident=[True])["accident"] == []
    assert load(seed=2, accident=[True])["accident"] == []
    for bad in ({"accident": [1, 0]}, {"accident": "yes"}, {"accident": [False] * 10},
                {"accident": [True], "h1_m2": {"0": "x"}}, {"accident": [True], "h1_m2": {"5": 1.0}},
                {"accident": [True], "h1_m2": []}):
        with pytest.raises(InputError, match="run directory .* is damaged: validation.ckpt"):
            load(**bad)
    path.write_text("[" * 50000)  # a write cut short or worse: the slices are run again
    assert _validation_checkpoint(path, fix, 2, planned=9)["accident"] == []
