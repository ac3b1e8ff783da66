"""Ctrl-C in every command that writes: exit 130, one line saying what was kept, and no file
that looks complete but is not."""

from __future__ import annotations

import json
import os
import pkgutil
import signal

import pytest

from rocas.recording.formats import open_recording


def _on_call(monkeypatch, target: str, calls: int, action) -> None:
    """Run ``action()`` on call number ``calls + 1`` of ``target`` (``module.attr`` or
    ``module.Class.method``) and on every later call, then make the call."""
    owner_path, _, attr = target.rpartition(".")
    owner = pkgutil.resolve_name(owner_path)
    original = getattr(owner, attr)
    seen = {"n": 0}

    def wrapper(*args, **kwargs):
        seen["n"] += 1
        if seen["n"] > calls:
            action(seen["n"] - calls)
        return original(*args, **kwargs)

    monkeypatch.setattr(owner, attr, wrapper)


def _interrupt_after(monkeypatch, target: str, calls: int) -> None:
    """Make ``target`` raise KeyboardInterrupt on call number ``calls + 1``."""
    def interrupt(_: int) -> None:
        raise KeyboardInterrupt

    _on_call(monkeypatch, target, calls, interrupt)


def _terminate_after(monkeypatch, target: str, calls: int) -> None:
    """Make ``target`` send SIGTERM to this process on call number ``calls + 1`` (and go on)."""
    def terminate(nth: int) -> None:
        if nth == 1:
            os.kill(os.getpid(), signal.SIGTERM)

    _on_call(monkeypatch, target, calls, terminate)


class _SigtermNotHandled(Exception):
    pass


@pytest.fixture
def sigterm_guard():
    """A SIGTERM that rocas does not handle ends in this exception, not in the end of pytest."""
    def fallback(signum, frame):
        raise _SigtermNotHandled

    previous = signal.signal(signal.SIGTERM, fallback)
    yield
    signal.signal(signal.SIGTERM, previous)


def _only_line(stderr: str) -> str:
    lines = [ln for ln in stderr.splitlines() if ln.startswith("rocas: error:")]
    assert len(lines) == 1, stderr
    assert "Traceback" not in stderr
    return lines[0]


@pytest.fixture
def example_toml():
    from importlib import resources

    return str(resources.files("rocas.scenarios") / "examples" / "junction_straight.toml")


def test_simulate_interrupted_while_recording_leaves_nothing(rocas, monkeypatch, tmp_path,
                                                             example_toml):
    _interrupt_after(monkeypatch, "rocas.recording.writer.RecordingWriter.write", 200)
    out = tmp_path / "run.mcap"
    res = rocas("simulate", example_toml, "-o", out, "--no-progress")
    assert res.code == 130
    assert _only_line(res.stderr) == "rocas: error: interrupted (no output was written)"
    assert os.listdir(tmp_path) == []


def test_replay_interrupted_while_recording_leaves_nothing(rocas, monkeypatch, tmp_path,
                                                           red_truck_recording):
    _interrupt_after(monkeypatch, "rocas.recording.writer.RecordingWriter.write", 100)
    res = rocas("replay", red_truck_recording, "-o", tmp_path / "replay.mcap")
    assert res.code == 130
    assert "no output was written" in _only_line(res.stderr)
    assert os.listdir(tmp_path) == []


def test_annotate_interrupted_while_copying_leaves_nothing(rocas, monkeypatch, tmp_path,
                                                           red_truck_recording):
    _interrupt_after(monkeypatch, "mcap.writer.Writer.add_message", 100)
    res = rocas("annotate", red_truck_recording, "--control-channel", "/control",
                "-o", tmp_path / "annotated.mcap")
    assert res.code == 130
    assert "no output was written" in _only_line(res.stderr)
    assert os.listdir(tmp_path) == []


def test_catalog_record_keeps_the_finished_recordings(rocas, monkeypatch, tmp_path):
    from rocas.catalog import entries

    first, second = entries()[:2]
    _interrupt_after(monkeypatch, "rocas.rollout.simulate", 1)
    res = rocas("catalog", "record", tmp_path, "--only", first.id, "--only", second.id)
    assert res.code == 130
    line = _only_line(res.stderr)
    assert f"1 complete recording kept in {tmp_path}: {first.key}.mcap" in line
    assert sorted(os.listdir(tmp_path)) == [f"{first.key}.mcap"]
    # the kept file is whole: it has its summary and the outcome record
    rec = open_recording(tmp_path / f"{first.key}.mcap").scan()
    assert "rocas.run" in dict(rec.metadata)


def test_catalog_generate_keeps_the_finished_scenario_files(rocas, monkeypatch, tmp_path):
    from rocas.catalog import entries

    first, second = entries()[:2]
    _interrupt_after(monkeypatch, "rocas.catalog.generate_instances", 1)
    res = rocas("catalog", "generate", "--instances", "1", "-o", tmp_path,
                "--only", first.id, "--only", second.id)
    assert res.code == 130
    files = os.listdir(tmp_path)
    assert len(files) == 1 and files[0].endswith(".toml")
    assert f"1 complete scenario file kept in {tmp_path}: {files[0]}" in _only_line(res.stderr)


def test_bench_says_the_run_directories_resume(rocas, monkeypatch, tmp_path):
    _interrupt_after(monkeypatch, "rocas.pipeline.bench.analyze", 0)
    res = rocas("bench", "--out", tmp_path / "bench", "A9")
    assert res.code == 130
    line = _only_line(res.stderr)
    assert f"kept in {tmp_path / 'bench'}" in line and "resumes" in line


def test_sigterm_stops_like_ctrl_c_with_exit_143(rocas, monkeypatch, tmp_path, example_toml,
                                                 sigterm_guard):
    _terminate_after(monkeypatch, "rocas.recording.writer.RecordingWriter.write", 200)
    out = tmp_path / "run.mcap"
    res = rocas("simulate", example_toml, "-o", out, "--no-progress")
    assert res.code == 143, res.stderr
    assert _only_line(res.stderr) == "rocas: error: interrupted (no output was written)"
    assert "Warning" not in res.stderr
    assert os.listdir(tmp_path) == []


@pytest.mark.slow  # about 20 s
def test_sigterm_keeps_the_finished_phases_of_an_analysis(rocas, monkeypatch, tmp_path,
                                                          sigterm_guard):
    out = tmp_path / "run"
    args = ["analyze", "roundabout_red_truck", "--scenario", "--out", out, "--budget", "16",
            "--population", "8", "--validation", "4", "--workers", "1", "--json"]
    _terminate_after(monkeypatch, "rocas.pipeline.analyze.phase_diff", 0)
    res = rocas(*args)
    assert res.code == 143, res.stderr
    assert f"kept in {out}; continue with --resume" in _only_line(res.stderr)
    assert set(json.loads((out / "state.json").read_text())["done"]) == {"replay", "physical"}
    monkeypatch.undo()
    assert rocas(*args, "--resume").code == 0
