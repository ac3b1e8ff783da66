"""A channel that differs from its first bin on, without a change point: its departure is in
its baseline, where Algorithm 1's window cannot see it unless the diff times it there
(rocas.analysis.diff, BASELINE_DEPARTURE_SIGMAS)."""

import importlib
import math

import pytest

from rocas.analysis import diff
from rocas.msgs import control_pb2
from rocas.recording import RecordingWriter

S = 1_000_000_000
TICKS = 60  # 6 s at 10 Hz
#: the module (rocas.analysis re-exports a function of the same name)
diff_module = importlib.import_module("rocas.analysis.diff")


def _run(path, offset, *, differs_at=2.0):
    """prediction -> /prediction -> planning -> /planning -> control -> /control. /prediction
    carries a wobbling value shifted by ``offset`` from the second message on; /planning and
    /control take ``offset`` from ``differs_at`` s on."""
    with RecordingWriter(path) as w:
        w.add_channel("/prediction", control_pb2.ControlCommand, writers=["prediction"],
                      readers=["planning"])
        w.add_channel("/planning", control_pb2.ControlCommand, writers=["planning"],
                      readers=["control"])
        w.add_channel("/control", control_pb2.ControlCommand, writers=["control"], role="control")
        for i in range(TICKS):
            t, ns = i / 10, i * S // 10
            shift = offset if i > 0 else 0.0  # both runs start alike
            wobble = 0.05 * math.sin(1.7 * i) * (1.0 + shift)
            w.write("/prediction", control_pb2.ControlCommand(throttle=0.3 + shift + wobble),
                    log_time_ns=ns)
            later = offset if t >= differs_at - 1e-9 else 0.0
            w.write("/planning", control_pb2.ControlCommand(throttle=0.2 + later), log_time_ns=ns)
            w.write("/control", control_pb2.ControlCommand(throttle=0.1 + later), log_time_ns=ns)
    return path


def _diff(tmp_path, offset):
    return diff(_run(tmp_path / "a.mcap", 0.0), _run(tmp_path / "b.mcap", offset))


def test_a_channel_far_from_the_other_run_from_its_first_bin_departs_there(tmp_path):
    r = _diff(tmp_path, 0.4)
    prediction = next(c for c in r.channels if c.topic == "/prediction")
    assert prediction.change_point_s is None                 # no change point ...
    assert r.deviating_module == "prediction"                # ... but the walk reaches it
    assert r.pinpoint.t_star[("channel", "/prediction")] == pytest.approx(0.0, abs=0.11)


def test_without_the_rule_the_walk_stops_downstream(tmp_path, monkeypatch):
    monkeypatch.setattr(diff_module, "BASELINE_DEPARTURE_SIGMAS", math.inf)
    assert _diff(tmp_path, 0.4).deviating_module == "planning"
