"""What the CLI tests share: a stand-in for the ``rerun`` viewer process, and ``rocas view``
serving without a display."""

from __future__ import annotations

import io
import os
import subprocess
import sys
from pathlib import Path

import pytest


class FakeViewer:
    """Stands in for ``subprocess.Popen`` of the ``rerun`` executable: records its argv and
    exits with ``exit_code`` (None: keeps running) after writing ``stderr``."""

    def __init__(self, exit_code=None, stderr=b""):
        self.exit_code, self.stderr_bytes, self.argv = exit_code, stderr, None

    def __call__(self, argv, **kwargs):
        self.argv = argv
        fake = self

        class Proc:
            pid = 4242
            stderr = io.BytesIO(fake.stderr_bytes)

            def wait(self, timeout=None):
                if fake.exit_code is None:
                    raise subprocess.TimeoutExpired(argv, timeout)
                return fake.exit_code

        return Proc()


@pytest.fixture
def fake_viewer():
    """``fake_viewer(exit_code=None, stderr=b"")`` -> a :class:`FakeViewer`."""
    return FakeViewer


def _serve_view(args, env=None):
    """Start ``rocas view ...`` serving without a display; return the process and its first
    line of output."""
    root = Path(__file__).resolve().parents[2]
    env = dict(os.environ, PYTHONPATH=os.pathsep.join([str(root), os.environ.get("PYTHONPATH", "")]),
               **(env or {}))
    env.pop("DISPLAY", None)
    env.pop("WAYLAND_DISPLAY", None)
    proc = subprocess.Popen([sys.executable, "-m", "rocas", "view", *map(str, args)], cwd=root,
                            env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    return proc, proc.stdout.readline()


@pytest.fixture
def serve_view():
    """``serve_view(args, env=None)`` -> (the ``rocas view`` process, its first line)."""
    return _serve_view
