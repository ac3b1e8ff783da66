"""docs/examples/python_stack.py, the worked example of docs/own-stack.md, runs as written."""

import subprocess
import sys
from pathlib import Path

from rocas.recording.formats import open_recording

EXAMPLE = Path(__file__).resolve().parents[2] / "docs" / "examples" / "python_stack.py"


def test_the_python_stack_example_runs_and_records_its_channels(tmp_path):
    proc = subprocess.run([sys.executable, str(EXAMPLE), str(tmp_path)], capture_output=True,
                          text=True, timeout=300, check=False)
    assert proc.returncode == 0, proc.stderr
    assert "1000 messages" in proc.stdout and "{'control.gap_m': 4.0} collision" in proc.stdout
    rec = open_recording(tmp_path / "follow.mcap").scan()
    assert set(rec.topics()) == {"/follow/ahead", "/follow/accel"}
    assert dict(rec.metadata)["rocas.stack"] == {"name": "follow"}
