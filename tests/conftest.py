import dataclasses
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


@pytest.fixture(scope="session")
def red_truck_recording(tmp_path_factory):
    """A 9 s recording of the roundabout red-truck example (hard brake at ~6.8 s)."""
    from rocas.scenarios import load_example
    from rocas.sim.engine import simulate

    path = tmp_path_factory.mktemp("red_truck") / "roundabout.mcap"
    simulate(dataclasses.replace(load_example("roundabout_red_truck"), duration_s=9.0), output=path)
    return path
