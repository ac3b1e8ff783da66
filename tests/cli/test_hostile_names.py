"""Names from data are never markup and never terminal control: topic and module names that
are rich markup (``[/``, ``[bold]``) or escape sequences (``\\r\\x1b[2K``) print as they read,
escaped, in every command's text output, and end no command with an internal error."""

from __future__ import annotations

import json

import pytest
from hostile import MARKUP, SPOOF, TOPIC, hostile_pair

from rocas._text import printable

ESC = "\x1b"


@pytest.fixture(scope="module")
def pair(tmp_path_factory):
    return hostile_pair(tmp_path_factory.mktemp("hostile"))


def _literal(res):
    """The output holds no control character, and names print as they read."""
    assert res.code == 0, res.stderr
    assert "internal error" not in res.stderr and "Traceback" not in res.stderr
    for text in (res.stdout, res.stderr):
        assert ESC not in text and "\r" not in text


def test_diff_prints_hostile_names_literally(rocas, pair):
    res = rocas("diff", *pair, "--allow-unrelated")
    _literal(res)
    assert f"Initial deviating module: {printable(SPOOF)}" in res.stdout
    assert MARKUP in res.stdout and printable(TOPIC) in res.stdout
    # the spoofed line is never a line of its own
    assert not any(line.startswith("Initial deviating module: planning")
                   for line in res.stdout.splitlines())


def test_cmg_prints_hostile_names_literally(rocas, pair):
    res = rocas("cmg", pair[0])
    _literal(res)
    assert f"  {MARKUP}: reads {printable(TOPIC)}" in res.stdout
    assert printable(SPOOF) in res.stdout
    res = rocas("cmg", pair[0], "--format", "json")  # JSON keeps the names as they are
    assert res.code == 0 and SPOOF in json.loads(res.stdout)["modules"]


def test_view_prints_hostile_names_literally(rocas, pair, tmp_path):
    res = rocas("view", pair[0], "--rrd", tmp_path / "v.rrd", "--no-viewer")
    _literal(res)
    assert printable(TOPIC) in res.stdout


def test_a_hostile_cmg_file_and_a_hostile_error(rocas, pair, tmp_path):
    cmg = tmp_path / "cmg.json"
    cmg.write_text(json.dumps({"modules": {MARKUP: {"reads": [], "writes": ["/vehicle/actuation"]}}}))
    res = rocas("cmg", pair[0], "--cmg", cmg)
    _literal(res)
    assert MARKUP in res.stdout
    # an error whose message carries a name: one line, shown escaped
    res = rocas("cmg", pair[0], "--control-channel", "/no\r\x1b[2Kwhere[/]")
    assert res.code == 3 and ESC not in res.stderr and "\r" not in res.stderr
    assert len(res.stderr.strip().splitlines()) == 1 and "internal error" not in res.stderr
