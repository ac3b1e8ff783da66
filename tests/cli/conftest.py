"""What the CLI tests share: a stand-in for the ``rerun`` viewer process."""

from __future__ import annotations

import io
import subprocess

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
