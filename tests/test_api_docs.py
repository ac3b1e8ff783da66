"""docs/api.md's examples run as written (from the repository's root, each block in a fresh
interpreter), and ``import rocas`` offers what the page says."""

from __future__ import annotations

import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PAGE = ROOT / "docs" / "api.md"
BLOCKS = re.findall(r"```python\n(.*?)```", PAGE.read_text(encoding="utf-8"), re.S)


def _run(code: str) -> subprocess.CompletedProcess[str]:
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    return subprocess.run([sys.executable, "-c", code], cwd=ROOT, env=env, capture_output=True,
                          text=True, timeout=600, check=False)


def test_the_page_has_its_examples():
    assert len(BLOCKS) == 5
    assert sum("rocas.analyze(" in b for b in BLOCKS) == 1


@pytest.mark.parametrize("index", [i for i, b in enumerate(BLOCKS) if "rocas.analyze(" not in b])
def test_an_example_runs_as_written(index):
    done = _run(BLOCKS[index])
    assert done.returncode == 0, done.stderr[-2000:]


@pytest.mark.slow
@pytest.mark.parametrize("index", [i for i, b in enumerate(BLOCKS) if "rocas.analyze(" in b])
def test_the_analysis_example_runs_as_written(index):
    done = _run(BLOCKS[index])
    assert done.returncode == 0, done.stderr[-2000:]


def test_import_rocas_offers_the_api_and_loads_nothing_heavy():
    code = ("import sys, rocas\n"
            "names = ['diff', 'analyze', 'simulate', 'replay', 'Report', 'DiffResult',\n"
            "         'RunResult', 'RocasError', 'UsageError', 'InputError', 'AnalyzeConfig']\n"
            "assert all(n in dir(rocas) for n in names), names\n"
            "assert 'numpy' not in sys.modules and 'rocas.pipeline' not in sys.modules\n"
            "assert callable(rocas.diff) and rocas.Report.__name__ == 'Report'\n")
    done = _run(code)
    assert done.returncode == 0, done.stderr[-2000:]


def test_an_unknown_analysis_setting_is_a_usage_error(tmp_path):
    import rocas

    with pytest.raises(rocas.UsageError, match="unknown analysis setting 'budgt'"):
        rocas.analyze(ROOT / "recordings" / "a09_red_truck_roundabout.mcap", tmp_path / "x",
                      budgt=3)
    assert not (tmp_path / "x").exists()
