"""Runs ``test_ray_executor.py`` in a child pytest process and reports its outcome here.

Ray ends its driver's process (exit code 1, no traceback) when its local cluster dies, for
example when the raylet or the GCS is killed or starved; inside the suite's own process that would
end the whole run without a report. In a child, a failing Ray test fails this test with the
child's output, and a cluster that dies is seen as what it is: the child is run once more, and if
Ray dies again the test is skipped with Ray's last words (the machine cannot run a local Ray),
never passed."""

from __future__ import annotations

import os
import subprocess
import sys
import xml.etree.ElementTree as ET
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
TESTS = Path(__file__).with_name("test_ray_executor.py")


def _run_child(report: Path) -> subprocess.CompletedProcess[str]:
    env = dict(os.environ, ROCAS_RAY_CHILD="1")
    return subprocess.run([sys.executable, "-m", "pytest", str(TESTS), "-p", "no:cacheprovider",
                           "-m", "", f"--junitxml={report}"], cwd=ROOT, env=env,
                          capture_output=True, text=True, timeout=900)


def _counts(report: Path) -> dict[str, int] | None:
    """tests/failures/errors/skipped of the child's JUnit report, or None if it wrote none (it
    ended before pytest could report: Ray ended it)."""
    if not report.exists():
        return None
    suite = ET.parse(report).getroot()
    suite = suite if suite.tag == "testsuite" else suite.find("testsuite")
    return {k: int(suite.get(k, 0)) for k in ("tests", "failures", "errors", "skipped")}


def _tail(done: subprocess.CompletedProcess[str], lines: int = 30) -> str:
    return "\n".join((done.stdout + "\n" + done.stderr).strip().splitlines()[-lines:])


@pytest.mark.slow  # starts a Ray cluster, about 20 s
def test_the_ray_executor_tests_in_a_child_process(tmp_path):
    pytest.importorskip("ray")
    deaths = []
    for attempt in range(2):
        report = tmp_path / f"child-{attempt}.xml"
        done = _run_child(report)
        counts = _counts(report)
        if counts is None:
            deaths.append(f"exit code {done.returncode}:\n{_tail(done)}")
            continue
        assert done.returncode == 0 and not counts["failures"] and not counts["errors"], (
            f"the Ray tests failed in the child:\n{_tail(done, 80)}")
        assert counts["tests"] >= 4 and not counts["skipped"], (counts, _tail(done))
        return
    pytest.skip("Ray's local cluster ended the test process twice on this machine; last time "
                + deaths[-1])
