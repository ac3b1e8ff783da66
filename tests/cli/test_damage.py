"""Damaged, partial or mismatched recordings (issue 21): refused, or answered with a warning.

One test per finding of the issue; each fails on the code before the fix.
"""

from __future__ import annotations

import errno
import io
import json
import signal
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from foreign_stack import make_pair
from fuzz.mutate import CHUNK, layout
from mcap.writer import Writer

from rocas.analysis.changepoints import ChangePointConfig, detect
from rocas.cli.console import Env
from rocas.cli.main import main
from rocas.msgs import control_pb2
from rocas.recording import open_recording, register_protobuf_channel

RECORDINGS = Path(__file__).resolve().parents[2] / "recordings"


@pytest.fixture(scope="module")
def pair(tmp_path_factory):
    return make_pair(tmp_path_factory.mktemp("pair"), deviating="tracker")


def _chunks(data: bytes) -> list[tuple[int, int]]:
    return [(off, size) for off, op, size in layout(data).records if op == CHUNK]


# -- finding 1: the summary's counts are compared with what was read ---------------------------


@pytest.mark.parametrize("how", ["remove", "duplicate"])
def test_a_removed_or_repeated_chunk_is_named_by_the_summary_check(rocas, pair, tmp_path, how):
    data = pair.accident.read_bytes()
    off, size = _chunks(data)[2]
    bad = tmp_path / "bad.mcap"
    if how == "remove":
        bad.write_bytes(data[:off] + data[off + size :])
    else:
        bad.write_bytes(data[: off + size] + data[off : off + size] + data[off + size :])
    rec = open_recording(bad)
    for _ in rec.messages():
        pass
    assert not rec.report.intact
    text = "\n".join(rec.report.warnings("bad"))
    assert "the summary section lists" in text and "chunk index" in text
    res = rocas("diff", bad, pair.reference, "--json")
    assert res.code == 0, res.stderr
    doc = json.loads(res.stdout)
    assert doc["complete"] is False
    assert any("summary section lists" in w for w in doc["warnings"])
    assert "rocas: warning:" in res.stderr


def test_an_intact_pair_is_complete(rocas):
    demo = RECORDINGS / "demo"
    res = rocas("diff", demo / "a01_scripted_accident.mcap", demo / "a01_scripted_reference.mcap",
                "--json")
    assert res.code == 0, res.stderr
    doc = json.loads(res.stdout)
    assert doc["complete"] is True and doc["warnings"] == []


def test_a_damaged_summary_is_not_trusted(pair, tmp_path):
    data = bytearray(pair.accident.read_bytes())
    data[-60] ^= 0xFF  # inside the summary section, before the footer
    bad = tmp_path / "bad.mcap"
    bad.write_bytes(bytes(data))
    rec = open_recording(bad)
    assert rec.summary()[0] is None and "summary section is damaged" in rec.summary()[1]
    assert rec.summary_start_time_ns() is None


# -- finding 2: replay carries the reader's damage warnings, in JSON mode too -------------------


def test_replay_of_a_damaged_recording_warns_and_says_incomplete(rocas, red_truck_recording,
                                                                tmp_path):
    data = Path(red_truck_recording).read_bytes()
    off, size = _chunks(data)[-1]
    bad = tmp_path / "bad.mcap"
    bad.write_bytes(data[: off + size] + data[off : off + size] + data[off + size :])
    res = rocas("replay", bad, "--json")
    assert res.code in (0, 4), res.stderr
    doc = json.loads(res.stdout)
    assert doc["complete"] is False and doc["warnings"]
    assert "rocas: warning:" in res.stderr and "summary section lists" in res.stderr


# -- finding 3: cmg reads the messages it reports on --------------------------------------------


def test_cmg_refuses_a_file_whose_chunks_are_all_unreadable(rocas, pair, tmp_path):
    data = bytearray(pair.accident.read_bytes())
    for off, _ in _chunks(bytes(data)):
        for k in range(80, 90):
            data[off + k] ^= 0x5A
    bad = tmp_path / "bad.mcap"
    bad.write_bytes(bytes(data))
    res = rocas("cmg", bad)
    assert res.code == 3, res.stdout
    assert "no readable message" in res.stderr


# -- finding 4: degenerate recordings -------------------------------------------------------------


def _write(path: Path, times_ns: list[int]) -> None:
    with open(path, "wb") as f:
        w = Writer(f)
        w.start()
        cid = register_protobuf_channel(w, "/control", control_pb2.ControlCommand,
                                        writers=["control"], role="control")
        for i, t in enumerate(times_ns):
            w.add_message(cid, log_time=t, publish_time=t,
                          data=control_pb2.ControlCommand(throttle=i % 7).SerializeToString())
        w.finish()


def test_a_one_message_recording_is_refused(rocas, tmp_path):
    one, ref = tmp_path / "one.mcap", tmp_path / "ref.mcap"
    _write(one, [0])
    _write(ref, [i * 10**8 for i in range(100)])
    res = rocas("diff", one, ref)
    assert res.code == 3
    assert "all at one log time" in res.stderr


def test_timestamps_that_wrap_past_2_64_are_refused(rocas, tmp_path):
    wrapped, ref = tmp_path / "wrapped.mcap", tmp_path / "ref.mcap"
    start = 2**64 - 5 * 10**9
    _write(wrapped, [(start + i * 10**8) % 2**64 for i in range(100)])
    _write(ref, [i * 10**8 for i in range(100)])
    res = rocas("diff", wrapped, ref)
    assert res.code == 3, res.stderr
    assert "wrapped past 2^64" in res.stderr


# -- finding 5: a pair that is not two runs of the same thing -------------------------------------


def test_two_different_accidents_are_refused(rocas):
    res = rocas("diff", RECORDINGS / "a01_creeping_car_junction.mcap",
                RECORDINGS / "a02_parked_pair_gap.mcap")
    assert res.code == 3
    assert "do not look like two runs of the same thing" in res.stderr
    res = rocas("diff", RECORDINGS / "a01_creeping_car_junction.mcap",
                RECORDINGS / "a02_parked_pair_gap.mcap", "--allow-unrelated", "--json")
    assert res.code == 0
    assert json.loads(res.stdout)["complete"] is False


# -- finding 6: change points in noise are not verdicts -------------------------------------------


def test_a_change_point_in_noise_is_not_kept_and_a_real_one_is():
    rng = np.random.default_rng(0)
    t = np.arange(30_000) * 0.1
    noise = np.clip(0.3 + 0.03 * np.sin(t / 300) + rng.normal(0, 0.03, t.size), 0, 1)
    assert detect(noise, t, ChangePointConfig(significance=0)).times_s  # PELT alone: noise
    assert detect(noise, t, ChangePointConfig()).times_s == ()
    step = noise.copy()
    step[20_000:] += 0.2
    assert detect(step, t, ChangePointConfig()).first_s == pytest.approx(2000.0)


# -- finding 7: a full disk is an output error ----------------------------------------------------


class _FullDisk(io.StringIO):
    def flush(self) -> None:
        raise OSError(errno.ENOSPC, "No space left on device")


def test_stdout_on_a_full_disk_exits_5(pair):
    err = io.StringIO()
    code = main(["cmg", str(pair.accident), "--format", "json"],
                env=Env(stdout=_FullDisk(), stderr=err))
    assert code == 5
    assert "No space left on device" in err.getvalue() and "internal error" not in err.getvalue()


# -- finding 9: smaller ones --------------------------------------------------------------------


@pytest.mark.parametrize("target, words", [("/dev/null", "is empty"), (".", "is a directory")])
def test_replay_names_dev_null_and_a_directory_for_what_they_are(rocas, target, words):
    res = rocas("replay", target)
    assert res.code == 3
    assert words in res.stderr and "no such file" not in res.stderr


def test_a_mistyped_control_channel_is_refused_before_reading(pair, monkeypatch):
    import importlib

    diff_mod = importlib.import_module("rocas.analysis.diff")

    def never(*a, **k):
        raise AssertionError("the recordings were read")

    monkeypatch.setattr(diff_mod, "compute_series", never)
    with pytest.raises(diff_mod.TopologyError, match="/no/such"):
        diff_mod.diff(pair.accident, pair.reference, control_channel_topic="/no/such")


def test_sigint_stops_rocas_started_with_sigint_ignored(pair):
    # a script's 'rocas ... &' starts it with SIGINT ignored
    code = ("import sys, time, rocas.cli.main as m\n"
            "import rocas.cli.cmg as c\n"
            "def slow(args, env):\n    print('ready', file=sys.stderr, flush=True)\n"
            "    time.sleep(30)\n    return 0\n"
            "c.run = slow\n"
            f"sys.exit(m.main(['cmg', {str(pair.accident)!r}]))\n")
    proc = subprocess.Popen([sys.executable, "-c", code], stderr=subprocess.PIPE, text=True,
                            preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_IGN))
    assert proc.stderr is not None
    assert proc.stderr.readline().strip() == "ready"
    proc.send_signal(signal.SIGINT)
    _, err = proc.communicate(timeout=20)
    assert proc.returncode == 130, err
