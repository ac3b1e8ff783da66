"""rocas analyze end to end on a shipped example (small budgets: these check the machinery;
accuracy over the catalog is measured by `rocas bench`)."""

import json
from dataclasses import replace
from pathlib import Path

import pytest

from rocas._json import rounded
from rocas.errors import OutputError, UsageError
from rocas.pipeline import VERDICTS, AnalyzeConfig
from rocas.pipeline import analyze as _analyze
from rocas.pipeline.validation import ROBUST_TOLERANCE, STRONGER_FRACTIONS, validation_simulations
from rocas.scenarios import load_example
from rocas.search import LocalExecutor, SerialExecutor

CFG = AnalyzeConfig(seed=1, budget=16, population=8, validation_variants=4)
REPORT_KEYS = {"verdict", "accident", "triggering_entity", "deviating_module", "misconfiguration",
               "validation", "evaluations", "timings_s"}


def analyze(*args, **kwargs):
    """The analysis's report as its report.json object (the shape these tests read)."""
    return _analyze(*args, **kwargs).to_json()


def _stable(report):
    return {k: v for k, v in report.items() if k != "timings_s"}


@pytest.fixture(scope="module")
def red_truck():
    return load_example("roundabout_red_truck")


@pytest.fixture(scope="module")
def serial_run(red_truck, tmp_path_factory):
    out = tmp_path_factory.mktemp("serial") / "run"
    return out, analyze(red_truck, out, CFG, executor=SerialExecutor())


def test_report_json_is_the_same_bytes_as_before_the_results_were_typed(serial_run):
    """data/red_truck/report.json was written, with these settings, by rocas before the phase
    results were typed (its floats unrounded: report.json now writes 12 significant digits,
    rocas._json); only the timings differ from run to run."""
    from rocas._json import dumps as json_dumps

    out, _ = serial_run
    stored = json.loads((Path(__file__).parent / "data" / "red_truck" / "report.json").read_text())
    fresh = json.loads((out / "report.json").read_text())
    fresh["timings_s"] = stored["timings_s"]
    assert json.dumps(fresh, indent=2) == json_dumps(stored, indent=2)


def test_state_json_reads_back_as_the_phases_typed_results(serial_run):
    from rocas.pipeline.rundir import read_state

    out, _ = serial_run
    state = read_state(out)
    assert list(state.results) == ["replay", "physical", "diff", "confidence", "cyber", "validation"]
    assert state.to_json() == json.loads((out / "state.json").read_text())


def test_report_has_the_documented_keys_and_files(serial_run):
    out, report = serial_run
    assert REPORT_KEYS <= set(report)
    assert report["verdict"] in VERDICTS
    assert report["accident"]["kind"] == "emergency"
    for name in ("state.json", "scenario.json", "replay.json", "accident.mcap", "report.json",
                 "report.md"):
        assert (out / name).exists(), name

    assert json.loads((out / "report.json").read_text()) == rounded(report)  # 12 digits
    # every JSON file of the run is standard JSON (no Infinity or NaN), for tools other than ours
    def refuse(constant):
        raise AssertionError(f"non-standard JSON constant {constant}")

    for f in out.glob("*.json"):
        json.loads(f.read_text(), parse_constant=refuse)
    if report["triggering_entity"]:
        assert (out / "reference.mcap").exists() and (out / "diff.json").exists()
        assert report["evaluations"]["physical"] > 0
    if report["verdict"] == "misconfiguration":
        v = report["validation"]
        assert [s["fraction"] for s in v["stronger"]] == list(STRONGER_FRACTIONS)
        assert report["evaluations"]["validation"] == validation_simulations(CFG.validation_variants)
        rob = v["robust_fix"]
        assert rob is None or rob["success_rate"] >= v["success_rate_fixed"] + ROBUST_TOLERANCE
        assert "**Robust value**" in (out / "report.md").read_text()
        # the phase's own file keeps exact values; the report rounds them (rocas._json)
        assert rounded(json.loads((out / "validation.json").read_text())) == rounded(v)


def test_same_result_whatever_the_executor(red_truck, serial_run, tmp_path):
    _, serial = serial_run
    with LocalExecutor(workers=2) as pool:
        parallel = analyze(red_truck, tmp_path / "run", CFG, executor=pool)
    assert _stable(parallel) == _stable(serial)


@pytest.mark.slow  # about 25 s
def test_resume_after_an_interruption_gives_the_same_report(red_truck, serial_run, tmp_path):
    _, serial = serial_run
    out = tmp_path / "run"

    def stop_at_diff(phase, info):
        if phase == "diff":
            raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        analyze(red_truck, out, CFG, executor=SerialExecutor(), progress=stop_at_diff)
    state = json.loads((out / "state.json").read_text())
    assert set(state["done"]) == {"replay", "physical"}
    physical_written = (out / "physical.json").stat().st_mtime_ns
    resumed = analyze(red_truck, out, CFG, executor=SerialExecutor(), resume=True)
    assert _stable(resumed) == _stable(serial)
    assert (out / "physical.json").stat().st_mtime_ns == physical_written  # not recomputed


def test_an_existing_run_dir_needs_resume(red_truck, serial_run):
    out, _ = serial_run
    with pytest.raises(UsageError, match="--resume"):
        analyze(red_truck, out, CFG, executor=SerialExecutor())
    with pytest.raises(UsageError, match="other settings"):
        analyze(red_truck, out, AnalyzeConfig(seed=2, budget=16, population=8), resume=True,
                executor=SerialExecutor())


def test_a_run_dir_that_cannot_be_made_is_an_output_error(red_truck, tmp_path):
    (tmp_path / "taken").write_text("keep")
    for out in (tmp_path / "taken", tmp_path / "taken" / "run"):
        with pytest.raises(OutputError, match=f"cannot make run directory {out}"):
            analyze(red_truck, out, CFG, executor=SerialExecutor())
    assert (tmp_path / "taken").read_text() == "keep"


def test_a_run_dir_from_before_a_setting_existed_resumes_with_its_default(red_truck, serial_run,
                                                                        tmp_path):
    import shutil

    src, serial = serial_run
    out = tmp_path / "run"
    shutil.copytree(src, out)
    state = json.loads((out / "state.json").read_text())
    del state["config"]["screening"]  # as written before the setting was added
    (out / "state.json").write_text(json.dumps(state))
    assert _stable(analyze(red_truck, out, CFG, executor=SerialExecutor(), resume=True)) == _stable(serial)
    with pytest.raises(UsageError, match="other settings"):
        analyze(red_truck, out, replace(CFG, screening=False), executor=SerialExecutor(), resume=True)


@pytest.mark.slow  # about 15 s
def test_without_screening_the_cyber_search_starts_at_its_first_generation(red_truck, serial_run,
                                                                          tmp_path):
    screened, _ = serial_run
    out = tmp_path / "run"
    analyze(red_truck, out, replace(CFG, screening=False), executor=SerialExecutor())
    plain = json.loads((out / "cyber.json").read_text())["generations"]
    first = json.loads((screened / "cyber.json").read_text())["generations"][0]
    # screening is generation 0: each parameter of the module alone at the ends of its range
    # and halfway to each (a value that is the parameter's current one is not simulated)
    n = json.loads((screened / "cyber.json").read_text())["parameters"]
    assert first["generation"] == 0 and 2 * n < first["evaluations"] <= 4 * n
    assert plain[0]["generation"] == 1 and plain[0]["evaluations"] <= CFG.population


def test_a_clean_run_is_not_reproduced(red_truck, tmp_path):
    from rocas.pipeline.physical import apply_physical
    from rocas.search.space import Mutation

    brown = apply_physical(red_truck, Mutation({"actor.red_truck.color": "brown"}))
    report = analyze(brown, tmp_path / "run", CFG, executor=SerialExecutor())
    assert report["verdict"] == "not_reproduced"
    assert report["triggering_entity"] is None and report["misconfiguration"] == []
    assert "gives no accident" in report["explanation"]


@pytest.mark.slow  # three whole analyses, about 110 s
def test_resume_inside_the_cyber_search_gives_the_same_report(red_truck, tmp_path):
    # a search resumed from its checkpoint, then the shrink and the choice among shrunk fixes
    # (which uses the gaps to other road users the simulations measured) as without the stop;
    # without screening, since a screening that finds a fix ends the search before generation 1
    cfg = AnalyzeConfig(seed=1, budget=96, population=8, validation_variants=4, screening=False)
    whole = analyze(red_truck, tmp_path / "whole", cfg)
    out = tmp_path / "run"

    def stop_in_cyber(phase, info):
        if phase == "cyber" and info.get("generation", 0) >= 2:
            raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        analyze(red_truck, out, cfg, progress=stop_in_cyber)
    assert (out / "cyber.ckpt").exists()
    resumed = analyze(red_truck, out, cfg, resume=True)
    assert _stable(resumed) == _stable(whole)


@pytest.mark.parametrize("bad", [
    {"delta_s": -1.0}, {"delta_s": float("nan")}, {"delta_s": float("inf")}, {"population": 1},
    {"population": 0}, {"seed": -1}, {"budget": 0}, {"executor": "bogus"}, {"workers": 0},
    {"validation_variants": -1}, {"h1_limit_m2": float("nan")}, {"k_suspicion": 0.0},
    {"batch_size": 0}, {"shrink_candidates": 0}, {"scope": "everything"}])
def test_every_bad_setting_is_refused_when_the_settings_are_made(bad):
    with pytest.raises(UsageError) as err:
        replace(CFG, **bad)
    assert err.value.hint  # what to do


def test_a_run_that_stops_before_any_phase_finished_leaves_no_folder_it_made(red_truck, tmp_path):
    def stop(phase, info):
        raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        analyze(red_truck, tmp_path / "new" / "run", CFG, executor=SerialExecutor(), progress=stop)
    assert not (tmp_path / "new").exists()
    # a folder that was there before stays, and so does anything in the way
    (tmp_path / "mine").mkdir()
    with pytest.raises(KeyboardInterrupt):
        analyze(red_truck, tmp_path / "mine", CFG, executor=SerialExecutor(), progress=stop)
    assert (tmp_path / "mine").is_dir()


def test_the_input_is_identified_by_content(red_truck, serial_run, tmp_path):
    import shutil

    from rocas.pipeline.rundir import source_identity

    a, b = tmp_path / "a.mcap", tmp_path / "b.mcap"
    a.write_bytes(b"same bytes")
    b.write_bytes(b"same bytes")
    assert source_identity(a)[1] == source_identity(b)[1]
    b.write_bytes(b"other bytes")  # replaced in place
    assert source_identity(a)[1] != source_identity(b)[1]
    # a scenario of the same name but other content is another input
    src, serial = serial_run
    out = tmp_path / "run"
    shutil.copytree(src, out)
    other = replace(red_truck, duration_s=red_truck.duration_s - 1.0)
    assert other.name == red_truck.name
    with pytest.raises(UsageError, match="another input"):
        analyze(other, out, CFG, executor=SerialExecutor(), resume=True)
    # a run directory from before: identified by its label, as it was then
    state = json.loads((out / "state.json").read_text())
    del state["source_sha256"]
    (out / "state.json").write_text(json.dumps(state))
    assert _stable(analyze(red_truck, out, CFG, executor=SerialExecutor(), resume=True)) == _stable(serial)
    with pytest.raises(UsageError, match="another input"):
        analyze(replace(red_truck, name="renamed"), out, CFG, executor=SerialExecutor(), resume=True)


def test_a_settings_mismatch_names_the_settings(red_truck, serial_run):
    out, _ = serial_run
    with pytest.raises(UsageError, match=r"seed 2 vs 1, budget 24 vs 16"):
        analyze(red_truck, out, replace(CFG, seed=2, budget=24), resume=True, executor=SerialExecutor())


def test_temporaries_a_killed_run_left_are_debris(red_truck, serial_run, tmp_path):
    import shutil

    from rocas.pipeline.rundir import prepare_run_dir

    # killed during the replay: nothing but a temporary
    out = tmp_path / "killed"
    out.mkdir()
    (out / ".accident.mcap.x1y2z3.part").write_bytes(b"half")
    state = prepare_run_dir(out, False, "label", CFG, "digest")
    assert state.results == {} and list(out.iterdir()) == []
    # ... and resumed later: the temporary goes, the run goes on
    src, serial = serial_run
    shutil.copytree(src, tmp_path / "run")
    (tmp_path / "run" / ".reference.mcap.abcd.part").write_bytes(b"half")
    assert _stable(analyze(red_truck, tmp_path / "run", CFG, executor=SerialExecutor(),
                           resume=True)) == _stable(serial)
    assert not list((tmp_path / "run").glob("*.part"))
    # a temporary beside other files is not rocas's to remove
    (tmp_path / "mine").mkdir()
    (tmp_path / "mine" / "notes.txt").write_text("keep")
    (tmp_path / "mine" / ".notes.txt.1234.part").write_text("keep")
    with pytest.raises(UsageError, match="not a rocas run directory"):
        analyze(red_truck, tmp_path / "mine", CFG, executor=SerialExecutor())
    assert len(list((tmp_path / "mine").iterdir())) == 2


def test_the_report_names_the_settings_that_produced_it(serial_run):
    from rocas.pipeline.config import REPORT_SETTINGS

    out, report = serial_run
    assert report["settings"] == {k: getattr(CFG, k) for k in REPORT_SETTINGS}
    assert "executor" not in report["settings"] and "workers" not in report["settings"]
    assert "- **Settings**: seed 1, budget 16, population 8," in (out / "report.md").read_text()


@pytest.mark.slow  # about 12 s
def test_a_damaged_run_directory_is_an_input_error(red_truck, serial_run, tmp_path):
    import shutil

    from rocas.errors import InputError

    src, _ = serial_run
    out = tmp_path / "run"
    shutil.copytree(src, out)
    text = (out / "state.json").read_text()
    (out / "state.json").write_text(text[: len(text) // 2])
    with pytest.raises(InputError, match="state.json") as err:
        analyze(red_truck, out, CFG, executor=SerialExecutor(), resume=True)
    assert f"delete {out}" in err.value.hint
    # a search checkpoint cut short by a crash (the cyber search without screening: a screening
    # that finds a fix, here the physical one, ends its search before any generation)
    out = tmp_path / "ckpt"
    plain = replace(CFG, screening=False)

    def stop_after_a_generation(phase, info):  # the first one is checkpointed by then
        if phase == "cyber" and info.get("generation", 0) > 1:
            raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        analyze(red_truck, out, plain, executor=SerialExecutor(), progress=stop_after_a_generation)
    ckpt = out / "cyber.ckpt"
    ckpt.write_bytes(ckpt.read_bytes()[:100])
    with pytest.raises(InputError, match="cyber.ckpt") as err:
        analyze(red_truck, out, plain, executor=SerialExecutor(), resume=True)
    assert "delete" in err.value.hint


def test_the_budget_rule_and_the_planned_simulations():
    from rocas.pipeline.config import planned_simulations

    default = AnalyzeConfig()
    # the defaults: 4 cyber generations after a 36-parameter screening (up to 4 x 36 = 144
    # simulations; perception's screening runs 125)
    assert default.search(2, 36).generations == 4 and default.search(1).generations == 10
    assert planned_simulations(default.search(2, 36), 125) == 125 + 3 * 24 <= default.budget
    assert planned_simulations(default.search(1)) == 240
    # a screening that uses up the budget is still followed by a generation of new mutants
    small = AnalyzeConfig(budget=48, population=12)
    assert small.search(2, 36).generations == 2
    assert planned_simulations(small.search(2, 36), 63) == 75
    assert planned_simulations(replace(small, screening=False).search(2, 36)) == 48


def test_a_screening_that_finds_a_fix_ends_the_cyber_search(serial_run):
    """The fix is then chosen among what every seed screens alike (a screening without a fix
    is followed by generations: tests/search/test_ga.py)."""
    out, report = serial_run
    cyber = json.loads((out / "cyber.json").read_text())
    assert report["verdict"] == "misconfiguration" and cyber["first_fix_evaluation"] is not None
    assert [g["generation"] for g in cyber["generations"]] == [0]
    physical = json.loads((out / "physical.json").read_text())
    assert physical["search"] == "screening" and physical["screening_feasible"] > 0


@pytest.mark.slow  # a second whole analysis (about 30 s)
def test_another_seed_gives_the_same_report_when_the_screenings_decide(red_truck, serial_run, tmp_path):
    out, report = serial_run
    other = analyze(red_truck, tmp_path / "run", replace(CFG, seed=CFG.seed + 1),
                    executor=SerialExecutor())
    same = ("verdict", "triggering_entity", "deviating_module", "path", "misconfiguration",
            "alternatives")
    assert {k: other[k] for k in same} == {k: report[k] for k in same}
    # the searches ran the same simulations; phase V's variants depend on the seed, and with them
    # where its sweep is settled
    searches = lambda r: {k: n for k, n in r["evaluations"].items() if k != "validation"}  # noqa: E731
    assert searches(other) == searches(report)


def test_the_report_prints_hostile_names_literally(serial_run):
    """A module, a topic and a parameter named like markup or a terminal escape print as they
    read in rocas analyze's report (they ended it with an internal error after the analysis)."""
    import io

    from hostile import MARKUP, SPOOF, TOPIC

    from rocas._text import printable
    from rocas.cli.analyze import render
    from rocas.cli.console import Env
    from rocas.pipeline.report import Report

    out, report = serial_run
    hostile = json.loads(json.dumps(report))
    hostile["deviating_module"] = SPOOF
    hostile["path"] = [TOPIC, MARKUP, SPOOF]
    hostile["explanation"] = f"{hostile['explanation']} {MARKUP} {SPOOF}"
    hostile["warnings"] = [f"channel {TOPIC} [bold]"]
    stdout = io.StringIO()
    render(Report.from_json(hostile), out, Env(stdout=stdout, stderr=io.StringIO()))
    text = stdout.getvalue()
    assert "\x1b" not in text and "\r" not in text
    assert f"{printable(SPOOF)}   walk: {printable(TOPIC)} -> {MARKUP}" in text
    assert f"channel {printable(TOPIC)} [bold]" in text
