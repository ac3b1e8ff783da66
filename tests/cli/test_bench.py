"""rocas bench's command line: --seeds (the bench itself: tests/pipeline/test_bench.py)."""

import json

import pytest


@pytest.mark.parametrize("bad", ["0,x", "-1", ","])
def test_a_bad_seed_list_is_refused_in_one_line(rocas, bad):
    res = rocas("bench", "a09", "--seeds", bad)
    assert res.code == 2 and "--seeds" in res.stderr and "Traceback" not in res.stderr


def test_the_seed_table_is_printed_per_entry_and_seed(rocas, monkeypatch, tmp_path):
    import rocas.pipeline.bench as bench

    def fake(ids, out, cfg, **kwargs):
        row = {"id": "a09", "type": "A9", "hit": cfg.seed == 0, "seconds": 20.0, "marks": {},
               "found": {"deviating_module": "perception" if cfg.seed == 0 else "planning",
                         "parameters": [], "trigger_entity": None, "changes": []},
               "expected": {"fixes": [], "deviating_module": "perception"}, "timings_s": {}}
        return {"entries": [row], "hits": int(row["hit"]), "total": 1}

    monkeypatch.setattr(bench, "run_bench", fake)
    res = rocas("bench", "a09", "--seeds", "0,1", "--out", tmp_path, "--json")
    assert res.code == 0, res.stderr
    out = json.loads(res.stdout)
    assert out["hits_per_seed"] == {"0": 1, "1": 0} and out["every_seed"] == 0
    assert out["entries"][0]["found"]["1"]["module"] == "planning"
