"""The Rerun view of a highway analysis: what the .rrd holds, read back from the file, and
``rocas analyze H.mcap --rrd`` / ``rocas view RUN_DIR`` on a highway recording."""

import dataclasses
from collections import defaultdict

import numpy as np
import pytest

pytest.importorskip("highway_env")
pytest.importorskip("rerun")

from rrd import read_rrd  # noqa: E402

from rocas.search import Mutation  # noqa: E402
from rocas.stacks.highway.__main__ import main as highway_main  # noqa: E402
from rocas.stacks.highway.accidents import entry  # noqa: E402
from rocas.stacks.highway.comutation import Analysis, apply_physical  # noqa: E402
from rocas.stacks.highway.substitution import second_opinion  # noqa: E402
from rocas.stacks.highway.view import write_analysis_rrd  # noqa: E402
from rocas.stacks.highway.world import simulate  # noqa: E402

from .scenes import PLANTED, WEAK_BRAKES  # noqa: E402

SECONDS = {"physical": 1.0, "diff": 0.1, "cyber": 2.0, "validation": 0.5}
SIMULATIONS = {"physical": 6, "diff": 2, "cyber": 40, "validation": 4}


def _analysis(scene=PLANTED) -> Analysis:
    """An analysis of the planted accident from real runs: the reference slows the crawling
    car (v1) further, the fix raises the acceleration limit."""
    accident = simulate(scene, WEAK_BRAKES, 0)
    reference = simulate(apply_physical(scene, Mutation({"v1.speed": 1.75})), WEAK_BRAKES, 0)
    fix = {"control.ACC_MAX": 3.33}
    fix_run = simulate(scene, {**WEAK_BRAKES, **fix}, 0)
    assert accident.collided and not reference.accident and not fix_run.accident
    opinion = second_opinion(scene, WEAK_BRAKES, 0)
    return Analysis(accident, reference, {"v1.speed": 1.75}, "perception", "driver", fix,
                    ({"planning.LANE_CHANGE_MIN_ACC_GAIN": 1.94},), fix_run,
                    ("perception", "control", "planning"), opinion, 3, 4, SECONDS,
                    SIMULATIONS)


@pytest.fixture(scope="module")
def analysis():
    return _analysis()


def _rows(path, entity: str, column: str) -> list:
    """Every row of one component of ``entity`` (static and temporal), in file order."""
    from rerun.chunk import RrdReader

    reader = RrdReader(path)
    (store,) = reader.recordings()
    out: dict[str, list] = defaultdict(list)
    for chunk in reader.stream(store=store):
        batch = chunk.to_record_batch()
        if str(chunk.entity_path) == entity and column in batch.schema.names:
            out[column] += batch.column(column).to_pylist()
    return out[column]


def _text(path, entity: str) -> str:
    (text,) = _rows(path, entity, "TextDocument:text")
    return text[0]


def test_the_rrd_holds_every_run_on_the_road_with_the_answer(analysis, tmp_path):
    out = tmp_path / "h.rrd"
    assert write_analysis_rrd(out, analysis, "planted.mcap") == ("accident", "reference", "fix")
    entities, blueprints = read_rrd(out)
    assert blueprints == 1
    for run, result in (("accident", analysis.accident), ("reference", analysis.reference),
                        ("fix", analysis.fix_run)):
        for part in ("ego/box", "ego/body", "vehicles/boxes", "vehicles/bodies"):
            info = entities[f"/world/{run}/{part}"]
            assert info.rows == len(result.times) and info.timelines == {"sim_time"}
        assert entities[f"/world/{run}/ego/path"].static_rows == 1
        for signal in ("speed", "acceleration", "steering"):
            assert entities[f"/signals/{run}/{signal}"].rows == len(result.times)
    # the crash only where there is one; the changed vehicle outlined in the two runs it
    # differs between, not in the fix run
    assert "/world/accident/crash" in entities and "/world/accident/crash/label" in entities
    assert not any(e.startswith(("/world/reference/crash", "/world/fix/crash")) for e in entities)
    assert "/world/accident/vehicles/changed" in entities
    assert "/world/fix/vehicles/changed" not in entities
    assert {"/world/road/surface", "/world/road/lines", "/world/road/stripes",
            "/report/verdict", "/report/diff", "/report/fix"} <= set(entities)


def test_the_crash_and_the_answer_read_as_text(analysis, tmp_path):
    out = tmp_path / "h.rrd"
    write_analysis_rrd(out, analysis, "planted.mcap")
    hit = analysis.accident.collided_with
    kind = PLANTED.others[hit - 1].kind
    (label,) = _rows(out, "/world/accident/crash/label", "Points2D:labels")
    assert label == [f"accident: collision with v{hit} ({kind}) at 7.20 s"]
    (time,) = _rows(out, "/world/accident/crash", "sim_time")
    assert time.total_seconds() == pytest.approx(analysis.accident.collision_t_s, abs=1e-6)
    (event,) = _rows(out, "/world/fix/events", "TextLog:text")
    assert event[0].startswith("fix: no accident in 12 s")
    fix = _text(out, "/report/fix")
    assert "| control.ACC_MAX | 1.82 | 3.33 |" in fix and "3 of 4" in fix
    assert "planning.LANE_CHANGE_MIN_ACC_GAIN = 1.94" in fix
    diff = _text(out, "/report/diff")
    assert "**Initial deviating module: perception**" in diff
    # the answer (control, the fix's module) is named by one reference's diff of three, and
    # ideal control avoids the weak brakes' crash: one of the two supports it
    assert "Confidence in **control**: **contested**." in diff
    assert "1 of 3 references' diffs name it" in diff
    assert "Module substitution agrees: ideal control avoids the accident" in diff
    assert "| v1.speed (trigger) | 2.484 | 1.75 |" in diff
    assert "the fix's, **control**" in diff  # the answer's module, revised to the fix's
    verdict = _text(out, "/report/verdict")
    assert verdict.startswith("# planted: misconfiguration") and "planted.mcap" in verdict


def test_the_road_is_highway_envs_and_the_vehicles_stand_where_they_drove(analysis, tmp_path):
    out = tmp_path / "h.rrd"
    write_analysis_rrd(out, analysis, "planted.mcap")
    # three 4 m lanes centred at y = 0, 4, 8: continuous edges at -2 and 10, stripes between
    (lines,) = _rows(out, "/world/road/lines", "LineStrips2D:strips")
    assert sorted({round(p[1], 6) for strip in lines for p in strip}) == [-2.0, 10.0]
    (stripes,) = _rows(out, "/world/road/stripes", "LineStrips2D:strips")
    assert {round(p[1], 6) for strip in stripes for p in strip} == {2.0, 6.0}
    assert all(np.hypot(*np.subtract(s[-1], s[0])) == pytest.approx(3.0, abs=1e-3) for s in stripes)
    bodies = _rows(out, "/world/accident/vehicles/bodies", "LineStrips2D:strips")
    labels = _rows(out, "/world/accident/vehicles/bodies", "LineStrips2D:labels")
    others = analysis.accident.others
    for k in (0, len(bodies) - 1):
        centres = np.array([np.mean(strip, axis=0) for strip in bodies[k]])
        np.testing.assert_allclose(centres, others[k, :, :2], atol=1e-3)  # float32 in the file
    assert labels[0] == [f"v{i} {o.kind}" for i, o in enumerate(PLANTED.others, start=1)]


def test_an_analysis_without_reference_or_fix_shows_the_accident_alone(tmp_path):
    e = entry("h06")
    accident = simulate(e.scene, e.params, e.seed)
    a = Analysis(accident, None, {}, None, "driver", {}, (), None, (), None, 0, 0, SECONDS,
                 SIMULATIONS)
    out = tmp_path / "h06.rrd"
    assert write_analysis_rrd(out, a) == ("accident",)
    entities, _ = read_rrd(out)
    assert not any(e.startswith(("/world/reference", "/world/fix", "/signals/fix")) for e in entities)
    assert _text(out, "/report/fix").startswith("# No configuration fix")
    assert "**No reference**" in _text(out, "/report/diff")


def test_names_from_the_data_are_text_never_paths_nor_markup(tmp_path):
    hostile = "../../x/`*[a](b)|\n<img src=x onerror=alert(1)>"
    a = _analysis(dataclasses.replace(PLANTED, name=hostile))
    out = tmp_path / "h.rrd"
    write_analysis_rrd(out, a, hostile)
    plain = _analysis()
    write_analysis_rrd(tmp_path / "plain.rrd", plain)
    entities, _ = read_rrd(out)
    assert set(entities) == set(read_rrd(tmp_path / "plain.rrd")[0])
    verdict = _text(out, "/report/verdict")
    assert "<img" not in verdict and "&lt;img" in verdict and "\\n" in verdict
    assert "\\`\\*\\[a\\](b)\\|" in verdict


def test_merge_v0s_obstacle_is_drawn(tmp_path):
    e = entry("h02")
    accident = simulate(e.scene, e.params, e.seed)
    a = Analysis(accident, None, {}, None, "driver", {}, (), None, (), None, 0, 0, SECONDS,
                 SIMULATIONS)
    out = tmp_path / "h02.rrd"
    write_analysis_rrd(out, a)
    (label,) = _rows(out, "/world/accident/crash/label", "Points2D:labels")
    assert "collision with an object on the road" in label[0]
    (boxes,) = _rows(out, "/world/road/objects", "LineStrips2D:strips")
    (box,) = boxes  # the end-of-ramp obstacle, 2 m square at (310, 8)
    np.testing.assert_allclose(np.mean(box[:4], axis=0), [310.0, 8.0], atol=1e-4)


def test_rocas_analyze_writes_the_view_and_rocas_view_opens_the_run_directory(
        rocas, tmp_path, capsys):
    assert highway_main(["record", "h06", str(tmp_path / "h06.mcap")]) == 0
    capsys.readouterr()
    run, rrd = tmp_path / "run", tmp_path / "h06.rrd"
    res = rocas("analyze", tmp_path / "h06.mcap", "--workers", "1", "--out", run, "--rrd", rrd)
    assert res.code == 0, res.stderr
    assert f"Rerun recording: {rrd}" in res.stdout
    assert rrd.read_bytes() == (run / "analysis.rrd").read_bytes()
    entities, blueprints = read_rrd(rrd)
    assert blueprints == 1 and "/world/accident/crash" in entities
    assert not any(e.startswith("/world/fix") for e in entities)
    assert _text(rrd, "/report/fix").startswith("# No configuration fix")
    copy = tmp_path / "copy.rrd"
    res = rocas("view", run, "--rrd", copy, "--no-viewer")
    assert res.code == 0, res.stderr
    assert copy.read_bytes() == rrd.read_bytes()


def test_an_unwritable_rrd_is_refused_before_the_analysis(rocas, tmp_path, capsys):
    assert highway_main(["record", "h06", str(tmp_path / "h06.mcap")]) == 0
    capsys.readouterr()
    res = rocas("analyze", tmp_path / "h06.mcap", "--out", tmp_path / "run",
                "--rrd", tmp_path / "missing" / "x.rrd")
    assert res.code != 0 and res.stderr.startswith("rocas: error: cannot write")
    assert not (tmp_path / "run").exists()
