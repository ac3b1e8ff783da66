"""rocas annotate, and the worked example of docs/own-stack.md end to end."""

from __future__ import annotations

import importlib.util
import io
import json
import subprocess
import sys
from pathlib import Path

import pytest

from rocas.analysis import diff
from rocas.cli.console import Env
from rocas.cli.main import main
from rocas.recording import open_recording

EXAMPLE = Path(__file__).resolve().parents[2] / "docs" / "examples" / "own_stack.py"


def run(*argv: str) -> tuple[int, str, str]:
    env = Env(stdout=io.StringIO(), stderr=io.StringIO())
    code = main([str(a) for a in argv], env=env)
    return code, env.stdout.getvalue(), env.stderr.getvalue()


@pytest.fixture(scope="module")
def example(tmp_path_factory):
    """Run the docs' script exactly as the page tells the reader to."""
    out = tmp_path_factory.mktemp("own-stack")
    done = subprocess.run([sys.executable, str(EXAMPLE), str(out)], capture_output=True,
                          text=True, timeout=60, check=False)
    assert done.returncode == 0, done.stderr
    assert "accident" in done.stdout
    return out


def _messages(path):
    return [(m.channel.topic, m.log_time_ns, m.publish_time_ns, m.sequence, m.data)
            for m in open_recording(path).messages()]


def test_worked_example_annotate_then_diff_finds_the_planner(example, tmp_path):
    accident, reference = example / "accident.mcap", example / "reference.mcap"
    cmg = example / "acme-cmg.json"
    code, out, _ = run("cmg", accident)
    assert code == 0 and "declares no topology" in out
    out_path = tmp_path / "accident-annotated.mcap"
    code, out, err = run("annotate", accident, "--cmg", cmg, "-o", out_path)
    assert code == 0 and err == ""
    assert "topology set on 3 channel(s): /acme/cmd, /acme/obstacle, /acme/plan" in out
    assert "control channel: /acme/cmd" in out and "300 messages" in out
    assert _messages(out_path) == _messages(accident)
    code, out, _ = run("cmg", out_path)
    assert "Nothing missing" in out and "Control channel: /acme/cmd (from metadata)" in out
    # the stored topology, the --cmg file and the attach_channel recording agree
    assert diff(out_path, reference).pinpoint.deviating_module == "planner"
    assert diff(accident, reference, cmg=cmg).pinpoint.deviating_module == "planner"
    assert diff(example / "attached.mcap", reference).pinpoint.deviating_module == "planner"


def test_attached_recording_needs_nothing_more(example):
    code, out, _ = run("cmg", example / "attached.mcap", "--format", "json")
    doc = json.loads(out)
    assert doc["hints"] == [] and doc["control_channel"] == "/acme/cmd"
    assert doc["modules"]["planner"] == {"reads": ["/acme/obstacle"], "writes": ["/acme/plan"]}


def test_example_types_are_not_rocas_types(example):
    spec = importlib.util.spec_from_file_location("own_stack_example", EXAMPLE)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    assert mod.SpeedPlan.DESCRIPTOR.full_name == "acme.av.SpeedPlan"
    names = {c.schema_name for c in open_recording(example / "accident.mcap").scan()
             .channels.values()}
    assert names == {"acme.av.Obstacle", "acme.av.SpeedPlan", "acme.av.Command"}


def test_control_channel_flag_alone_and_cmg_warnings(example, tmp_path):
    cmg = tmp_path / "cmg.json"
    cmg.write_text(json.dumps({"modules": {"planner": {"writes": ["/acme/plan", "/ghost"]}}}))
    out_path = tmp_path / "o.mcap"
    code, out, err = run("annotate", example / "accident.mcap", "--cmg", cmg,
                         "--control-channel", "/acme/cmd", "-o", out_path)
    assert code == 0
    assert "names channel /ghost, which is not in" in err and "ignored" in err
    topics = {c.topic: c.metadata for c in open_recording(out_path).scan().channels.values()}
    assert topics["/acme/plan"] == {"rocas.writers": "planner"}
    assert topics["/acme/cmd"] == {"rocas.role": "control"}


@pytest.mark.parametrize(
    ("argv", "code", "needle"),
    [
        (["{acc}", "-o", "{acc}", "--cmg", "{cmg}"], 2, "is the input recording"),
        (["{acc}", "-o", "{tmp}/o.mcap"], 2, "nothing to annotate"),
        (["{tmp}/nope.mcap", "-o", "{tmp}/o.mcap", "--cmg", "{cmg}"], 3, "no such file"),
        (["{acc}", "-o", "{tmp}/o.mcap", "--cmg", "{tmp}/bad.json"], 3, "not valid JSON"),
        (["{acc}", "-o", "{tmp}/o.mcap", "--control-channel", "/x"], 3, "'/x'"),
    ],
)
def test_bad_input_is_one_error_line_and_no_output(example, tmp_path, argv, code, needle):
    (tmp_path / "bad.json").write_text("[1,")
    argv = [a.format(acc=example / "accident.mcap", cmg=example / "acme-cmg.json",
                     tmp=tmp_path) for a in argv]
    before = (example / "accident.mcap").read_bytes()
    got, out, err = run("annotate", *argv)
    assert got == code and out == ""
    assert err.startswith("rocas: error: ") and needle in err
    assert len(err.strip().splitlines()) == 1
    assert not (tmp_path / "o.mcap").exists()
    assert (example / "accident.mcap").read_bytes() == before
