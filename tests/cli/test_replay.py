import json


def test_replay_json(rocas, red_truck_recording, tmp_path):
    out = tmp_path / "replay.mcap"
    r = rocas("replay", red_truck_recording, "-o", out, "--json")
    assert r.code == 0, r.stderr
    d = json.loads(r.stdout)
    assert d["reproduced"] is True
    assert d["accident"]["kind"] == "emergency" and d["original_accident"]["kind"] == "emergency"
    assert abs(d["accident"]["time_s"] - d["original_accident"]["time_s"]) <= 0.5
    assert d["ego_rmse_m"] < 0.2 and d["ego_max_error_m"] >= d["ego_rmse_m"]
    assert "outcome" in d and out.exists()


def test_replay_text_and_what_if(rocas, red_truck_recording):
    r = rocas("replay", red_truck_recording)
    assert r.code == 0 and "reproduced" in r.stdout and "RMSE" in r.stdout
    r = rocas("replay", red_truck_recording, "--set", "perception.brake_threshold=0.99", "--json")
    assert r.code == 0, r.stderr          # a what-if that avoids the accident is not a failure
    d = json.loads(r.stdout)
    assert d["reproduced"] is False and d["accident"] is None
    assert d["params"] == {"perception.brake_threshold": 0.99}


def test_replay_errors(rocas, tmp_path, red_truck_recording):
    r = rocas("replay", tmp_path / "missing.mcap")
    assert r.code == 3 and "no such file" in r.stderr
    r = rocas("replay", red_truck_recording, "--set", "perception.nope=1")
    assert r.code == 2 and "perception.nope" in r.stderr
    r = rocas("replay", red_truck_recording, "-o", tmp_path / "x.txt")
    assert r.code == 2


def test_not_reproduced_exits_4_after_the_report(rocas, red_truck_recording, monkeypatch):
    import rocas.replay.run as run_mod

    monkeypatch.setattr(run_mod, "same_accident", lambda a, b: False)
    r = rocas("replay", red_truck_recording, "--json")
    assert r.code == 4
    assert json.loads(r.stdout)["reproduced"] is False      # the report is still printed
    assert "did not reproduce" in r.stderr


def test_the_output_may_not_be_the_input_recording(rocas, red_truck_recording, tmp_path):
    import shutil

    copy = tmp_path / "a.mcap"
    shutil.copy(red_truck_recording, copy)
    before = copy.read_bytes()
    link = tmp_path / "link.mcap"
    link.symlink_to(copy)
    for out in (copy, link, tmp_path / "." / "a.mcap"):
        r = rocas("replay", copy, "-o", out)
        assert r.code == 2 and "is the input recording" in r.stderr, r.stderr
    assert copy.read_bytes() == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a.mcap", "link.mcap"]
