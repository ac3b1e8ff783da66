import dataclasses
import io
import os
from dataclasses import dataclass

import pytest
from hypothesis import settings

from rocas.cli.console import Env
from rocas.cli.main import main

# every property test draws the same examples on every run (CI must not depend on luck); explore
# new ones locally with HYPOTHESIS_PROFILE=explore pytest --hypothesis-seed=N
settings.register_profile("ci", derandomize=True)
settings.register_profile("explore", derandomize=False)
settings.load_profile(os.environ.get("HYPOTHESIS_PROFILE", "ci"))


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
