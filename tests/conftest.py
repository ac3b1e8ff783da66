import io
from dataclasses import dataclass

import pytest

from rocas.cli.console import Env
from rocas.cli.main import main


@dataclass
class Result:
    code: int
    stdout: str
    stderr: str


@pytest.fixture
def rocas():
    """Run the CLI in-process; returns exit code and captured output."""

    def run(*argv: str) -> Result:
        out, err = io.StringIO(), io.StringIO()
        code = main([str(a) for a in argv], env=Env(stdout=out, stderr=err))
        return Result(code, out.getvalue(), err.getvalue())

    return run
