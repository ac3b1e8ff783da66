import io
import json

from rocas.cli.console import Env
from rocas.cli.main import main
from rocas.recording.formats import open_recording


def _run(*argv):
    out, err = io.StringIO(), io.StringIO()
    status = main(list(argv), Env(stdout=out, stderr=err))
    return status, out.getvalue(), err.getvalue()


def test_simulate_writes_a_recording_and_one_line(tmp_path):
    path = tmp_path / "run.mcap"
    status, out, err = _run("simulate", "left_turn_oncoming", "-o", str(path), "--duration", "4",
                            "--set", "planning.yield_distance_m=3")
    assert status == 0, err
    assert out.count("\n") == 1 and "left_turn_oncoming:" in out and str(path) in out
    rec = open_recording(path)
    assert "/control" in {m.channel.topic for m in rec.decoded()}


def test_simulate_json_outcome_and_seed(tmp_path):
    path = tmp_path / "run.mcap"
    status, out, _ = _run("simulate", "left_turn_oncoming", "-o", str(path), "--duration", "3",
                          "--seed", "4", "--json", "--no-progress")
    assert status == 0
    data = json.loads(out)
    assert data["seed"] == 4 and data["collided"] is False and data["messages"] > 0


def test_bad_parameter_names_the_key(tmp_path):
    status, _, err = _run("simulate", "left_turn_oncoming", "-o", str(tmp_path / "x.mcap"),
                          "--set", "planning.nope=1")
    # an unknown --set parameter is a usage error (2), pointing to the command's help
    assert status == 2 and "planning.nope" in err and "unknown parameter" in err
    assert "rocas params --stack ads" in err
    assert "'rocas simulate --help'" in err
    assert not (tmp_path / "x.mcap").exists()


def test_bad_scenario_file_names_file_key_reason(tmp_path):
    bad = tmp_path / "bad.toml"
    bad.write_text('[scenario]\nname = "x"\nspeed = 3\n[[lanes]]\nid = "a"\n'
                   'points = [[0, 0], [10, 0]]\n[ego]\nroute = ["a"]\n')
    status, _, err = _run("simulate", str(bad), "-o", str(tmp_path / "x.mcap"))
    assert status == 3 and str(bad) in err and "scenario.speed" in err and "unknown key" in err
    status, _, err = _run("simulate", "no_such_example", "-o", str(tmp_path / "x.mcap"))
    assert status == 3 and "no example scenario" in err
