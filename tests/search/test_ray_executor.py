"""The Ray executor: one Ray task per batch, results in order, the same report as the local
executor. All tests share one local Ray (the session's ``ray_cluster``).

These tests run in a child pytest process (``test_ray_child.py`` starts it with
``ROCAS_RAY_CHILD=1``): when Ray's local cluster dies, Ray ends its driver process with exit code
1 and no traceback, which in the suite's own process would end the whole test run unreported."""

import dataclasses
import os

import pytest

from rocas.errors import InputError
from rocas.search.executor import executor_names, make_executor

CHILD_ENV = "ROCAS_RAY_CHILD"
pytestmark = pytest.mark.skipif(os.environ.get(CHILD_ENV) != "1",
                                reason="run in a child process by tests/search/test_ray_child.py")


@pytest.fixture
def ray_executor(ray_cluster):
    from rocas.search.ray_executor import RayExecutor

    ex = RayExecutor()
    yield ex
    ex.close()


def test_results_come_back_in_task_order_one_task_per_element(ray_executor):
    def work(batch):  # pickled by value: Ray's workers need not import the tests
        return [(x * x, os.getpid()) for x in batch]

    batches = [list(range(i, i + 3)) for i in range(0, 30, 3)]
    out = ray_executor.map(work, batches)
    assert [[sq for sq, _ in b] for b in out] == [[x * x for x in b] for b in batches]
    # each batch ran whole in one worker process, never split into individuals
    assert all(len({pid for _, pid in b}) == 1 for b in out)
    assert all(pid != os.getpid() for b in out for _, pid in b)
    assert ray_executor.workers == 2 and ray_executor.map(work, []) == []


def test_a_rocas_error_in_a_task_reaches_the_caller_as_itself(ray_executor):
    def fails(x):
        raise InputError(f"bad input {x}", "fix it")

    with pytest.raises(InputError, match="bad input 3"):
        ray_executor.map(fails, [3])


def test_registered_by_name_and_a_shared_ray_is_left_running(ray_cluster):
    assert "ray" in executor_names()
    ex = make_executor("ray", None)
    assert ex.name == "ray" and ex.workers == 2
    ex.close()
    assert ray_cluster.is_initialized()  # the session's Ray, not the executor's to end


@pytest.mark.slow
def test_same_seed_same_report_as_the_local_executor(ray_executor, tmp_path):
    from rocas.pipeline import AnalyzeConfig, analyze
    from rocas.scenarios import load_example
    from rocas.search import LocalExecutor

    scenario = dataclasses.replace(load_example("roundabout_red_truck"), duration_s=9.0)
    cfg = AnalyzeConfig(seed=1, budget=16, population=8, validation_variants=4)
    with LocalExecutor(workers=2) as local:
        expected = analyze(scenario, tmp_path / "local", cfg, executor=local).to_json()
    got = analyze(scenario, tmp_path / "ray", cfg, executor=ray_executor).to_json()
    expected.pop("timings_s")
    got.pop("timings_s")
    assert got == expected
    assert got["evaluations"]["physical"] > 0  # the searches ran, on Ray
