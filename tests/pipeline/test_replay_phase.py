"""Phase I: the original run the later phases compare against is the run phase I recorded, not a
second simulation of it."""

from pathlib import Path

import numpy as np
import pytest

from rocas.pipeline.config import AnalyzeConfig
from rocas.pipeline.evaluate import VariantTask, run_batch
from rocas.pipeline.replay_phase import phase_replay
from rocas.pipeline.rundir import Run, RunState, noop
from rocas.scenarios import load_example
from rocas.search import SerialExecutor

RECORDINGS = Path(__file__).resolve().parents[2] / "recordings"


class _Counting(SerialExecutor):
    """A serial executor that counts the tasks mapped over it."""

    def __init__(self) -> None:
        super().__init__()
        self.mapped = 0

    def map(self, fn, items):  # noqa: ANN001, ANN201
        items = list(items)
        self.mapped += len(items)
        return super().map(fn, items)


def _run(tmp_path: Path, executor: SerialExecutor) -> Run:
    return Run(tmp_path, AnalyzeConfig(), executor, noop, RunState("x", {}))


def _same(a, b) -> None:  # noqa: ANN001
    assert a.outcome == b.outcome
    np.testing.assert_array_equal(a.ego_xy, b.ego_xy)
    np.testing.assert_array_equal(a.actors_xy, b.actors_xy)


@pytest.mark.parametrize("source", ["recording", "scenario"])
def test_the_original_is_the_recorded_run_bit_for_bit(tmp_path: Path, source: str) -> None:
    executor = _Counting()
    run = _run(tmp_path, executor)
    if source == "recording":
        phase_replay(run, None, RECORDINGS / "a09_red_truck_roundabout.mcap")
    else:
        phase_replay(run, load_example("junction_straight"), None)
    assert executor.mapped == 0  # nothing simulated beyond the recorded run
    scn = run.scenario
    assert scn is not None and run.original is not None
    (again,) = run_batch([VariantTask(scn, (), scn.seed)])  # what phase I used to re-simulate
    _same(run.original, again)


def test_a_resumed_replay_re_simulates_the_original(tmp_path: Path) -> None:
    first = _run(tmp_path, SerialExecutor())
    phase_replay(first, None, RECORDINGS / "a09_red_truck_roundabout.mcap")
    executor = _Counting()
    resumed = Run(tmp_path, AnalyzeConfig(), executor, noop, first.state)
    phase_replay(resumed, None, None)
    assert executor.mapped == 1
    assert resumed.original is not None and first.original is not None
    _same(resumed.original, first.original)
    assert resumed.accident == first.accident and resumed.accident_tick == first.accident_tick


class _Submitting(SerialExecutor):
    """A serial executor with ``submit`` (as LocalExecutor's), noting what it was given."""

    def __init__(self) -> None:
        super().__init__()
        self.submitted: list[str] = []

    def submit(self, fn, *args):  # noqa: ANN001, ANN201
        from rocas.search.executor import done_future

        self.submitted.append(Path(args[-1]).name)
        return done_future(fn, *args)


def test_the_shrink_check_records_the_unshrunk_reference_apart_with_the_same_answer(
        tmp_path: Path) -> None:
    """Phase II's shrink check always records the unshrunk reference and the most shrunk step:
    the first is handed to a worker while this process records the second, and what it finds
    is what it finds with everything recorded here."""
    from rocas.pipeline.physical_phase import _settle
    from rocas.search.space import Mutation

    trail = [Mutation({"actor.obstacle_1.color": "black"}),
             Mutation({"actor.obstacle_1.color": "blue"})]
    found = []
    for name, executor in (("serial", SerialExecutor()), ("worker", _Submitting())):
        run = _run(tmp_path / name, executor)
        (tmp_path / name).mkdir()
        phase_replay(run, None, RECORDINGS / "a09_red_truck_roundabout.mcap")
        small, checked, path = _settle(run, trail)
        found.append((small, checked, path.name if path else None))
        if name == "worker":
            assert executor.submitted == ["shrink_0.mcap"]
    assert found[0] == found[1]
