"""Runs ``test_ray_executor.py`` in a child pytest process and reports its outcome here.

Ray ends its driver's process (exit code 1, no traceback) when its local cluster dies, for
example when the raylet or the GCS is killed or starved; inside the suite's own process that would
end the whole run without a report. In a child, a failing Ray test fails this test with the
child's output, and a cluster that dies is seen as what it is: the child is run once more, and if
Ray dies again the test is skipped with Ray's last words (the machine cannot run a local Ray),
never passed."""

from __future__ import annotations

import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
TESTS = Path(__file__).with_name("test_ray_executor.py")
#: the line pytest ends every completed run with ("4 passed in 21.3s", "1 failed, 3 passed ...")
_SUMMARY = re.compile(r"^=*\s*(\d+ (passed|failed|error|errors|skipped)\b.*) in [\d.]+s", re.M)


def _run_child() -> subprocess.CompletedProcess[str]:
    env = dict(os.environ, ROCAS_RAY_CHILD="1")
    return subprocess.run([sys.executable, "-m", "pytest", str(TESTS), "-p", "no:cacheprovider",
                           "-q", "-ra", "-m", ""], cwd=ROOT, env=env, capture_output=True,
                          text=True, timeout=900)


def _tail(done: subprocess.CompletedProcess[str], lines: int = 30) -> str:
    return "\n".join((done.stdout + "\n" + done.stderr).strip().splitlines()[-lines:])


def test_the_ray_executor_tests_in_a_child_process():
    pytest.importorskip("ray")
    deaths = []
    for _ in range(2):
        done = _run_child()
        summary = _SUMMARY.search(done.stdout)
        if summary is None:  # the child ended before pytest could report: Ray ended it
            deaths.append(f"exit code {done.returncode}:\n{_tail(done)}")
            continue
        assert done.returncode == 0, f"the Ray tests failed in the child:\n{_tail(done, 80)}"
        counts = dict((k, int(n)) for n, k in re.findall(r"(\d+) (passed|failed|skipped)",
                                                          summary.group(1)))
        assert counts.get("passed", 0) >= 4 and not counts.get("skipped"), summary.group(1)
        return
    pytest.skip("Ray's local cluster ended the test process twice on this machine; last time "
                + deaths[-1])
