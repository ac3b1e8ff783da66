"""rocas triage end to end on a small campaign (the session's ``small_campaign``)."""

import json

from rocas.campaign import collect_inputs


def test_campaign_lists_groups_and_failures_and_writes_its_files(small_campaign):
    out, c = small_campaign
    assert c["accidents_total"] == 2 and c["analysed"] == 1 and not c["complete"]
    [failed] = c["failed"]
    assert failed["name"] == "broken" and "not valid TOML" in failed["reason"]
    assert "\n" not in failed["reason"]
    [g] = c["groups"]
    [a] = c["accidents"]
    assert g["accidents"] == ["red_truck"] and a["group"] == g["id"]
    assert g["root_cause"] == a["root_causes"][0]
    assert a["confidence"]["level"] in ("stable", "contested", "unstable")
    assert json.loads((out / "campaign.json").read_text()) == c
    assert "broken" in (out / "campaign.md").read_text()
    assert (out / "runs" / "red_truck" / "report.json").exists()


def test_resume_reads_finished_accidents_back_and_refuses_without_it(small_campaign, rocas, monkeypatch,
                                                                     tmp_path):
    out, c = small_campaign
    src = [str(p) for p in collect_inputs([c["accidents"][0]["source"]])[0].path.parent.glob("*.toml")]
    args = ["triage", *src, "--out", out, "--seed", 1, "--budget", 16, "--population", 8,
            "--workers", 1, "--executor", "serial"]
    refused = rocas(*args)
    assert refused.code == 2 and "--resume" in refused.stderr

    def no_second_analysis(*a, **kw):
        raise AssertionError("a finished accident was analysed again")

    import importlib

    # the module (the package rocas.pipeline exports its function analyze under the same name)
    monkeypatch.setattr(importlib.import_module("rocas.pipeline.analyze"), "analyze", no_second_analysis)
    again = rocas(*args, "--resume", "--json")
    assert again.code == 0, again.stderr
    got = json.loads(again.stdout)
    assert got["groups"] == c["groups"] and got["failed"] == c["failed"]
    # a finished analysis made with other settings is not taken for this campaign's (in a copy:
    # the session's campaign stays as it is)
    import shutil

    shutil.copytree(out, tmp_path / "c")
    other_args = [*args[:args.index("--out") + 1], tmp_path / "c", *args[args.index("--out") + 2:]]
    other_args[other_args.index("--seed") + 1] = 2
    other = rocas(*other_args, "--resume", "--json")
    assert other.code == 0, other.stderr
    failed = {f["name"]: f["reason"] for f in json.loads(other.stdout)["failed"]}
    assert "other settings" in failed["red_truck"]


def test_a_recording_beside_its_ground_truth_is_one_accident(tmp_path):
    (tmp_path / "x.mcap").write_bytes(b"")
    (tmp_path / "x.toml").write_text('[ground_truth]\nid = "A3"\ntitle = "t"\n')
    (tmp_path / "y.toml").write_text("")
    items = collect_inputs([str(tmp_path)])
    assert [(i.name, i.kind, i.truth_type) for i in items] == [("x", "recording", "A3"),
                                                                 ("y", "scenario", None)]


def test_hostile_names_in_a_campaign_are_escaped_in_its_page_and_tables(small_campaign):
    """campaign.md embeds no HTML or Markdown from names, and the terminal tables print them as
    they read (they ended the table with a markup error)."""
    import io

    from hostile import MARKUP, SPOOF

    from rocas.campaign.triage import markdown
    from rocas.cli.console import Env
    from rocas.cli.triage import render

    out, c = small_campaign
    c = json.loads(json.dumps(c))
    evil = "<img src=x onerror=alert(1)>|" + MARKUP
    c["accidents"][0]["name"] = evil
    c["accidents"][0]["deviating_module"] = SPOOF
    c["groups"][0]["root_cause"] = evil
    c["failed"][0]["name"] = "`code` <script>"
    md = markdown(c)
    assert "<img" not in md and "<script>" not in md and "&lt;img src=x onerror=alert(1)&gt;" in md
    assert "\\|" in md and "\x1b" not in md and "\r" not in md
    stdout = io.StringIO()
    render(c, out, Env(stdout=stdout, stderr=io.StringIO()))
    text = stdout.getvalue()
    assert MARKUP in text.replace("\n", "") or "fore[/]" in text
    assert "\x1b" not in text and "\r" not in text
