"""The README's quick start: the plain install is enough, and running it twice works and leaves
nothing outside the run directory (issue 40)."""

import re
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
SMALL = ("--budget", "16", "--population", "8", "--validation", "2", "--workers", "1")
#: what the dev and ray extras add; the quick start must not need any of it
EXTRAS_ONLY = ("ray", "selenium", "pytest", "hypothesis", "grpc_tools", "ruff", "mcap_ros2",
               "ruptures")
#: runs the rocas CLI with the extras' modules made unimportable (a plain install)
PLAIN = """
import importlib.abc, sys
class _Plain(importlib.abc.MetaPathFinder):
    def find_spec(self, name, path=None, target=None):
        if name.split(".")[0] in {blocked!r}:
            raise ImportError(f"{{name}} is an extra, not in a plain install")
sys.meta_path.insert(0, _Plain())
from rocas.cli.main import console_script
sys.argv[0] = "rocas"
console_script()
"""


def quick_start_commands() -> list[str]:
    """The shell lines of the README's quick start block."""
    text = (ROOT / "README.md").read_text(encoding="utf-8")
    section = text.split("## Quick start", 1)[1]
    block = re.search(r"```bash\n(.*?)```", section, re.S).group(1)
    return [ln.strip() for ln in block.splitlines() if ln.strip() and not ln.startswith("#")]


def test_the_quick_start_is_a_plain_install_and_a_repeatable_analysis():
    lines = quick_start_commands()
    assert lines[0] == "pip install . -c constraints.txt"  # no extras
    analyze = next(ln for ln in lines if ln.startswith("rocas analyze"))
    assert "--replace" in analyze and "--rrd" not in analyze
    assert any(ln.startswith("rocas view runs/") for ln in lines)


def _rocas_plain(cwd: Path, *argv: str) -> subprocess.CompletedProcess:
    code = PLAIN.format(blocked=set(EXTRAS_ONLY))
    env = {"PYTHONPATH": str(ROOT), "PATH": "/usr/bin:/bin", "HOME": str(cwd)}
    return subprocess.run([sys.executable, "-c", code, *argv], cwd=cwd, env=env,
                          capture_output=True, text=True, timeout=600)


def test_the_extras_are_really_blocked(tmp_path):
    res = subprocess.run([sys.executable, "-c", PLAIN.format(blocked={"rich"}), "params"],
                         cwd=tmp_path, env={"PYTHONPATH": str(ROOT), "PATH": "/usr/bin:/bin"},
                         capture_output=True, text=True, timeout=120)
    assert res.returncode != 0 and "rich is an extra" in res.stderr


def test_replace_starts_afresh_and_removes_only_run_directories(rocas, tmp_path):
    out = tmp_path / "run"
    args = ("analyze", "roundabout_red_truck", "--scenario", "--out", out, *SMALL, "-q")
    assert rocas(*args).code == 0
    again = rocas(*args)
    assert again.code == 2 and "already holds an analysis" in again.stderr
    (out / "stale.txt").write_text("from the earlier run")
    replaced = rocas(*args, "--replace")
    assert replaced.code == 0, replaced.stderr
    assert not (out / "stale.txt").exists() and (out / "report.json").is_file()
    both = rocas(*args, "--replace", "--resume")
    assert both.code == 2 and "contradict" in both.stderr
    foreign = tmp_path / "mine"
    foreign.mkdir()
    (foreign / "thesis.tex").write_text("keep me")
    res = rocas("analyze", "roundabout_red_truck", "--scenario", "--out", foreign, *SMALL, "--replace")
    assert res.code == 2 and "not a rocas run directory" in res.stderr
    assert (foreign / "thesis.tex").read_text() == "keep me"


@pytest.mark.slow  # two whole analyses of the shipped A9 accident, about 30 s
def test_the_readme_quick_start_runs_twice_on_a_plain_install(tmp_path):
    shutil.copytree(ROOT / "recordings", tmp_path / "recordings")
    analyze = next(ln for ln in quick_start_commands() if ln.startswith("rocas analyze"))
    argv = analyze.split()[1:]
    for _ in range(2):
        res = _rocas_plain(tmp_path, *argv)
        assert res.returncode == 0, res.stderr
        assert "misconfiguration   perception.brake_threshold 0.8 -> 0.8549" in res.stdout
    view = next(ln for ln in quick_start_commands() if ln.startswith("rocas view"))
    assert (tmp_path / view.split()[2] / "report.json").is_file()
    strays = [p for p in tmp_path.rglob("*") if p.is_file() and "runs" not in p.relative_to(tmp_path).parts
              and p.relative_to(tmp_path).parts[0] != "recordings"]
    assert strays == []
