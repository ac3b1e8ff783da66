import json

from rocas.catalog import entries
from rocas.scenarios import load_scenario as load_scenario_text


def test_list_shows_every_entry(rocas):
    r = rocas("catalog", "list")
    assert r.code == 0, r.stderr
    for e in entries():
        assert e.id in r.stdout and e.truth.module in r.stdout


def test_list_json_gives_the_ground_truth(rocas):
    r = rocas("catalog", "list", "--json")
    assert r.code == 0
    data = json.loads(r.stdout)
    assert [d["id"] for d in data] == [e.id for e in entries()]
    a9 = next(d for d in data if d["id"] == "A9")
    assert a9["module"] == "perception" and a9["fix"] == {"perception.brake_threshold": 0.99}
    assert a9["consequence"] == "emergency" and a9["diff_module"] == "perception"


def test_generate_reports_counts_and_writes_loadable_scenarios(rocas, tmp_path):
    r = rocas("catalog", "generate", "--instances", "2", "--only", "A9", "-o", tmp_path,
              "--json")
    assert r.code == 0, r.stderr
    row = json.loads(r.stdout)[0]
    assert row["id"] == "A9" and row["tried"] >= row["crashed"] >= row["fix_holds"] >= row["kept"] == 2
    files = sorted(tmp_path.glob("a09_*.toml"))
    assert len(files) == 2
    assert load_scenario_text(files[0]).name == files[0].stem


def test_generate_says_how_many_variants_the_documented_fix_repairs(rocas):
    r = rocas("catalog", "generate", "--instances", "1", "--only", "A4", "--only", "A7")
    assert r.code == 0, r.stderr
    a4, a7 = r.stdout.splitlines()
    assert a4.startswith("A4: ") and "the documented fix repairs" in a4 and a4.endswith("kept 1")
    assert a7.startswith("A7: ") and "(no fix exists to check)" in a7


def test_record_writes_the_accident(rocas, tmp_path):
    r = rocas("catalog", "record", tmp_path, "--only", "A9")
    assert r.code == 0, r.stderr
    assert "A9: emergency" in r.stdout
    assert (tmp_path / f"{entries()[0].key}.mcap").exists() or list(tmp_path.glob("a09_*.mcap"))


def test_unknown_entry_and_bad_count_are_usage_errors(rocas, tmp_path):
    r = rocas("catalog", "record", tmp_path, "--only", "A99")
    assert r.code != 0 and "no catalog entry" in r.stderr
    r = rocas("catalog", "generate", "--instances", "0")
    assert r.code != 0 and "--instances" in r.stderr


def test_generate_family_writes_variants_with_their_ground_truth_and_recordings(rocas, tmp_path):
    from rocas.catalog.variants import load_variant

    r = rocas("catalog", "generate", "--family", "rotate", "--instances", "1", "--only", "A10",
              "-o", tmp_path, "--record", "--json")
    assert r.code == 0, r.stderr
    row = json.loads(r.stdout)[0]
    assert row["family"] == "rotate" and row["kept"] == 1
    assert row["tried"] >= row["crashed"] >= row["fix_holds"] >= 1
    (name,) = row["variants"]
    v = load_variant(tmp_path / f"{name}.toml")
    assert v.truth.id == "A10" and v.scenario.name == name
    assert (tmp_path / f"{name}.mcap").stat().st_size > 0


def test_generate_family_and_record_misuse_are_usage_errors(rocas, tmp_path):
    r = rocas("catalog", "generate", "--instances", "1", "--record", "-o", tmp_path)
    assert r.code != 0 and "--record needs --family" in r.stderr
    r = rocas("catalog", "generate", "--instances", "1", "--family", "teleport")
    assert r.code != 0 and "teleport" in r.stderr


def test_catalog_list_and_record_take_a_stack(tmp_path, capsys):
    import json as _json

    from rocas.cli.main import main

    assert main(["catalog", "list", "--stack", "lav", "--json"]) == 0
    listed = _json.loads(capsys.readouterr().out)
    assert [e["id"] for e in listed][:2] == ["L1", "L2"] and listed[0]["module"] == "brake"
    assert main(["catalog", "record", str(tmp_path), "--stack", "lav", "--only", "L1"]) == 0
    assert (tmp_path / "l01_red_truck_roundabout.mcap").is_file()
    assert main(["catalog", "generate", "--stack", "lav", "--family", "rotate",
                 "--instances", "1"]) == 2
    assert "does not declare variant families" in capsys.readouterr().err
    assert main(["catalog", "list", "--stack", "nope"]) == 2


def test_generate_per_type_tops_each_type_up_from_the_next_family(rocas, monkeypatch):
    """--per-type: K variants per type in all; a family is asked only for what the ones before
    did not make (at most --max-tries draws), and a type still short of K is named on stderr."""
    from types import SimpleNamespace

    import rocas.catalog.variants as variants

    asked = []
    kept_by = {("A3", "mixed"): 1, ("A3", "rotate"): 1, ("A10", "mixed"): 3}

    def fake(e, family, count, *, seed=0, max_tries=None):
        asked.append((e.id, family, count, seed, max_tries))
        n = min(count, kept_by.get((e.id, family), count))
        vs = [SimpleNamespace(name=f"{e.key}__{family}_k{i}", reference_avoids=True) for i in range(n)]
        return SimpleNamespace(tried=8, invalid=0, crashed=n, fix_holds=n, variants=vs)

    monkeypatch.setattr(variants, "generate_variants", fake)
    r = rocas("catalog", "generate", "--family", "mixed", "--family", "rotate", "--per-type",
              "--instances", "3", "--only", "A3", "--only", "A10", "--seed", "5", "--max-tries", "7",
              "--json")
    assert r.code == 0, r.stderr
    assert asked == [("A3", "mixed", 3, 5, 7), ("A3", "rotate", 2, 5, 7), ("A10", "mixed", 3, 5, 7)]
    assert [(row["id"], row["family"], row["kept"]) for row in json.loads(r.stdout)] == \
        [("A3", "mixed", 1), ("A3", "rotate", 1), ("A10", "mixed", 3)]
    assert "fewer than 3 variants kept for A3 (2 of 3)" in r.stderr
    # without --per-type every family makes K of each type
    asked.clear()
    r = rocas("catalog", "generate", "--family", "mixed", "--family", "rotate",
              "--instances", "3", "--only", "A10", "--json")
    assert r.code == 0 and asked == [("A10", "mixed", 3, 0, None), ("A10", "rotate", 3, 0, None)]
    r = rocas("catalog", "generate", "--per-type", "--instances", "3")
    assert r.code != 0 and "--per-type needs --family" in r.stderr
    r = rocas("catalog", "generate", "--family", "mixed", "--instances", "3", "--max-tries", "0")
    assert r.code != 0 and "--max-tries" in r.stderr


def test_a_stack_without_a_catalog_names_the_stacks_that_have_one(rocas, monkeypatch):
    from types import SimpleNamespace

    from rocas.stacks import registry

    monkeypatch.setitem(registry._registered, "bare", SimpleNamespace(name="bare"))
    for action in (["list"], ["record", "out"], ["generate", "--instances", "1"]):
        r = rocas("catalog", *action, "--stack", "bare")
        assert r.code == 2 and r.stderr.count("\n") == 1, action
        assert r.stderr.startswith("rocas: error: stack 'bare' has no accident catalog "
                                   "(catalogs exist for: ads, lav"), r.stderr
