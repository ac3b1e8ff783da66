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
    from rocas.rollout import simulate
    from rocas.scenarios import load_example

    path = tmp_path_factory.mktemp("red_truck") / "roundabout.mcap"
    simulate(dataclasses.replace(load_example("roundabout_red_truck"), duration_s=9.0), output=path)
    return path


@pytest.fixture(scope="session")
def ros2_pair(tmp_path_factory):
    """A short ROS 2 accident/reference pair written with mcap-ros2-support's Writer, and the
    ``--cmg`` file a ROS 2 user writes for it; prediction_node deviates first (at 7 s)."""
    import json

    from ros2_mix import ROS2_CMG, Ros2MixConfig, write_ros2_pair

    out = tmp_path_factory.mktemp("ros2")
    cfg = Ros2MixConfig(duration_s=12.0, obstacles=6, forecast_points=20, plan_points=30,
                        deviate_at_s=7.0)
    acc, ref = write_ros2_pair(out, cfg)
    cmg = out / "cmg.json"
    cmg.write_text(json.dumps(ROS2_CMG))
    return acc, ref, cmg


@pytest.fixture(scope="session")
def ray_cluster():
    """One local Ray (two CPUs) for the whole test run: starting one takes seconds. Skipped
    where Ray, an optional extra (``rocas[ray]``, part of the dev extras), is missing."""
    ray = pytest.importorskip("ray")
    from rocas.search.ray_executor import LOCAL_OBJECT_STORE_BYTES, _private_ray_environment

    started = not ray.is_initialized()
    if started:  # on loopback with its token, as the executor's own private Ray
        with _private_ray_environment(ray):
            ray.init(num_cpus=2, include_dashboard=False, log_to_driver=False,
                     configure_logging=False, object_store_memory=LOCAL_OBJECT_STORE_BYTES)
    yield ray
    if started:
        ray.shutdown()


@pytest.fixture(scope="session")
def small_campaign(tmp_path_factory):
    """A triaged campaign of two accidents (small budgets, in this process): the red-truck
    example as a scenario file, and a file that is not a scenario (listed as failed)."""
    from rocas.campaign import collect_inputs, triage
    from rocas.catalog import scenario_toml
    from rocas.pipeline import AnalyzeConfig
    from rocas.scenarios import load_example
    from rocas.search import SerialExecutor

    src = tmp_path_factory.mktemp("campaign_inputs")
    scenario = dataclasses.replace(load_example("roundabout_red_truck"), duration_s=9.0)
    (src / "red_truck.toml").write_text(scenario_toml(scenario))
    (src / "broken.toml").write_text("this is = not [a scenario\n")
    out = tmp_path_factory.mktemp("campaign") / "c"
    cfg = AnalyzeConfig(seed=1, budget=16, population=8, validation_variants=0)
    campaign = triage(collect_inputs([str(src)]), out, cfg, executor=SerialExecutor())
    return out, campaign
