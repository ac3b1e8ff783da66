"""The exit-code table, the one-line error format, --traceback and Ctrl-C (docs/errors.md)."""

from __future__ import annotations

import importlib
import json

import pytest
from foreign_stack import make_pair

from rocas.cli.exit_codes import ExitStatus, exit_status_for
from rocas.errors import (
    InputError,
    NotReproducedError,
    OutputError,
    RecordingError,
    RocasError,
    ScenarioError,
    Terminated,
    TopologyError,
    UsageError,
)

TABLE = [
    (UsageError("--bin must be positive", "give a bin width in seconds"), 2),
    (InputError("cannot read cmg.json", "check the path"), 3),
    (RecordingError("a.mcap is empty (0 bytes)", "give a non-empty MCAP recording"), 3),
    (TopologyError("no channel has topology", "pass --cmg FILE"), 3),
    (ScenarioError("speed must be positive", None), 3),
    (NotReproducedError("the replay did not collide", "widen the search"), 4),
    (OutputError("cannot write out.rrd: Permission denied", "choose a writable place"), 5),
    (RocasError("something rocas refused", None), 3),
]


@pytest.fixture(scope="module")
def pair(tmp_path_factory):
    return make_pair(tmp_path_factory.mktemp("errors"), deviating="behaviour")


def _raising(exc: BaseException):
    def fake_diff(*args, **kwargs):
        raise exc

    return fake_diff


def _patch_diff(monkeypatch, exc: BaseException) -> None:
    """Make the analysis behind ``rocas diff`` raise ``exc`` (the CLI imports it lazily)."""
    module = importlib.import_module("rocas.analysis.diff")
    monkeypatch.setattr(module, "diff", _raising(exc))


def test_the_documented_exit_codes():
    assert {s.name: int(s) for s in ExitStatus} == {
        "SUCCESS": 0, "INTERNAL": 1, "USAGE": 2, "INPUT": 3, "NOT_REPRODUCED": 4,
        "OUTPUT": 5, "INTERRUPTED": 130, "TERMINATED": 143,
    }
    assert exit_status_for(KeyboardInterrupt()) == 130
    assert exit_status_for(Terminated()) == 143
    assert exit_status_for(ZeroDivisionError()) == 1


@pytest.mark.parametrize(("exc", "code"), TABLE, ids=lambda x: type(x).__name__)
def test_each_error_is_one_line_with_its_exit_code(rocas, monkeypatch, pair, exc, code):
    assert exit_status_for(exc) == code
    _patch_diff(monkeypatch, exc)
    res = rocas("diff", pair.accident, pair.reference)
    assert res.code == code
    expected = f"rocas: error: {exc.message}" + (f" ({exc.hint})" if exc.hint else "")
    assert res.stderr == expected + "\n"
    assert res.stdout == ""


def test_a_bug_is_an_internal_error_that_asks_for_a_report(rocas, monkeypatch, pair):
    _patch_diff(monkeypatch, ZeroDivisionError("division by zero"))
    res = rocas("diff", pair.accident, pair.reference)
    assert res.code == 1
    lines = res.stderr.splitlines()
    assert len(lines) == 1
    assert lines[0].startswith("rocas: error: internal error: ZeroDivisionError: division by zero")
    assert "--traceback" in lines[0] and "Traceback" not in res.stderr


@pytest.mark.parametrize("where", ["before", "after"])
def test_traceback_shows_the_full_story(rocas, monkeypatch, pair, where):
    _patch_diff(monkeypatch, ZeroDivisionError("division by zero"))
    argv = ["diff", pair.accident, pair.reference]
    argv = ["--traceback", *argv] if where == "before" else [*argv, "--traceback"]
    res = rocas(*argv)
    assert res.code == 1
    assert "Traceback (most recent call last)" in res.stderr
    assert "fake_diff" in res.stderr  # the frame that raised
    assert res.stderr.rstrip().splitlines()[-1].startswith("rocas: error: internal error")


def test_ctrl_c_exits_130_and_says_nothing_was_written(rocas, monkeypatch, pair):
    _patch_diff(monkeypatch, KeyboardInterrupt())
    res = rocas("diff", pair.accident, pair.reference)
    assert res.code == 130
    assert res.stderr == "rocas: error: interrupted (no output was written)\n"


def test_ctrl_c_reports_what_was_kept(rocas, monkeypatch, pair):
    exc = KeyboardInterrupt()
    exc.kept = "kept 12 finished simulations in run/"
    _patch_diff(monkeypatch, exc)
    res = rocas("diff", pair.accident, pair.reference)
    assert res.code == 130
    assert res.stderr == "rocas: error: interrupted (kept 12 finished simulations in run/)\n"
    res = rocas("--traceback", "diff", pair.accident, pair.reference)
    assert res.code == 130 and "KeyboardInterrupt" in res.stderr


def test_ctrl_c_while_writing_the_rrd_leaves_no_file(rocas, monkeypatch, pair, tmp_path):
    def interrupted(rec, result, prefix="diff"):
        raise KeyboardInterrupt

    monkeypatch.setattr("rocas.viz.diff.log_diff", interrupted)
    out = tmp_path / "out" / "diff.rrd"
    out.parent.mkdir()
    res = rocas("diff", pair.accident, pair.reference, "--rrd", out)
    assert res.code == 130
    assert "interrupted (no output was written)" in res.stderr
    assert not out.exists()
    assert list(out.parent.iterdir()) == []  # no temporary file left behind either


def test_a_damaged_but_usable_recording_warns_and_succeeds(rocas, pair, tmp_path):
    data = bytearray(pair.accident.read_bytes())
    data[len(data) // 3 : len(data) // 3 + 64] = bytes(64)  # a run of zeros in mid-file
    bad = tmp_path / "zeros.mcap"
    bad.write_bytes(bytes(data))
    res = rocas("diff", bad, pair.reference, "--json")
    assert res.code == 0, res.stderr
    assert all(line.startswith("rocas: warning: ") for line in res.stderr.splitlines())
    assert str(bad) in res.stderr
    out = json.loads(res.stdout)
    assert out["warnings"] and out["messages_read"]["accident"] > 0


def test_nothing_usable_left_is_an_input_error(rocas, pair, tmp_path):
    head = pair.accident.read_bytes()[:40]  # magic + the start of the header record
    for name in ("a", "b"):
        (tmp_path / f"{name}.mcap").write_bytes(head)
    res = rocas("diff", tmp_path / "a.mcap", tmp_path / "b.mcap")
    assert res.code == 3
    line = res.stderr.splitlines()[-1]
    assert line.startswith("rocas: error: neither recording holds a readable message: ")
    assert "truncated" in line and line.endswith("(check the files with 'mcap info')")
    assert len(res.stderr.splitlines()) == 1


@pytest.mark.parametrize("where", ["a directory", "under a file"])
def test_an_output_that_cannot_be_written_is_refused_before_the_work(rocas, monkeypatch, pair,
                                                                     tmp_path, where):
    target = tmp_path / "out.rrd"
    if where == "a directory":
        target.mkdir()
    else:
        (tmp_path / "plain").write_text("x")
        target = tmp_path / "plain" / "out.rrd"
    _patch_diff(monkeypatch, AssertionError("the diff ran before the output was checked"))
    res = rocas("diff", pair.accident, pair.reference, "--rrd", str(target))
    assert res.code == 5 and res.stdout == ""
    assert res.stderr.startswith(f"rocas: error: cannot write {target}: ")
    assert res.stderr.count("\n") == 1
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted(
        ["out.rrd"] if where == "a directory" else ["plain"])


def test_traceback_is_accepted_after_every_command_and_action():
    from rocas.cli.main import build_parser

    parser = build_parser()
    for argv in (["catalog", "list", "--traceback"], ["catalog", "--traceback", "list"],
                 ["params", "--traceback"], ["--traceback", "catalog", "list"]):
        assert parser.parse_args(argv).traceback is True, argv


@pytest.mark.parametrize("command", [
    ("view", "{rec}", "--no-viewer", "--rrd", "{out}/x.rrd"),
    ("diff", "{rec}", "{rec}", "--rrd", "{out}/x.rrd"),
    ("simulate", "junction_straight", "-o", "{out}/x.mcap"),
    ("annotate", "{rec}", "--control-channel", "/control", "-o", "{out}/x.mcap"),
    ("analyze", "{rec}", "--out", "{out}/run"),
])
def test_a_missing_output_folder_exits_5_and_is_not_created(rocas, red_truck_recording, tmp_path,
                                                            command):
    missing = tmp_path / "nonexistent" / "dir"
    argv = [a.format(rec=red_truck_recording, out=missing) for a in command]
    res = rocas(*argv)
    assert res.code == 5, res.stderr
    assert "does not exist" in res.stderr and "mkdir -p" in res.stderr
    assert not (tmp_path / "nonexistent").exists()


def test_a_reader_that_stops_ends_rocas_quietly(rocas):
    """``rocas params --json | head``: a closed stdout is no error (exit 0, nothing on stderr)."""
    import io
    import os
    import subprocess
    import sys
    from pathlib import Path

    from rocas.cli.console import Env
    from rocas.cli.main import main

    class Closed(io.StringIO):
        def write(self, s):
            raise BrokenPipeError(32, "Broken pipe")

        def flush(self):
            raise BrokenPipeError(32, "Broken pipe")

    err = io.StringIO()
    assert main(["params", "--json"], env=Env(stdout=Closed(), stderr=err)) == 0
    assert err.getvalue() == ""
    root = Path(__file__).resolve().parents[2]
    env = {**os.environ, "PYTHONPATH": str(root)}
    for args in (["params", "--json"], ["catalog", "list", "--json"]):
        proc = subprocess.Popen([sys.executable, "-m", "rocas", *args], stdout=subprocess.PIPE,
                                stderr=subprocess.PIPE, env=env, cwd=root)
        proc.stdout.close()  # the reader is gone before rocas writes
        assert proc.wait(timeout=60) == 0
        assert proc.stderr.read() == b""
        proc.stderr.close()


def test_devices_and_huge_inputs_are_refused_in_one_line(rocas, tmp_path):
    from rocas._limits import MAX_INPUT_BYTES

    for args in (["simulate", "/dev/zero", "-o", tmp_path / "x.mcap"],
                 ["cmg", "/dev/null", "--cmg", "/dev/zero"]):
        res = rocas(*args)
        assert res.code == 3, res.stderr
        (line,) = res.stderr.strip().splitlines()
        assert line.startswith("rocas: error: /dev/zero: larger than "
                               f"{MAX_INPUT_BYTES // 2**20} MB, too large for a ")
    deep = tmp_path / "deep.json"
    deep.write_text("[" * 100000 + "]" * 100000)
    res = rocas("cmg", "/dev/null", "--cmg", deep)
    assert res.code == 3 and "nested more than 64 levels deep" in res.stderr
    assert "internal error" not in res.stderr
