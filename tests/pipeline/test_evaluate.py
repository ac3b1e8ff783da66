"""How evaluate groups simulations into batches and batches onto workers."""

import numpy as np
import pytest

from rocas.pipeline import evaluate as ev


class _Recorder:
    """An executor that records the batches it is given and returns placeholders."""

    name = "recorder"

    def __init__(self, workers):
        self.workers, self.batches = workers, []

    def map(self, fn, tasks):
        self.batches.append([len(t) for t in tasks])
        return [list(t) for t in tasks]

    def close(self):
        pass


@pytest.mark.parametrize(("tasks", "workers", "batches"), [
    (24, 2, [24]),            # a generation: one batch in this process
    (127, 2, [127]),          # too few to give each worker PARALLEL_MIN_BATCH
    (128, 2, [64, 64]),       # enough: one batch per worker
    (255, 2, [128, 127]),     # the validation's first wave at 200 variants
    (255, 1, [255]),          # one worker: one batch
    (600, 2, [150, 150, 150, 150]),  # more than a batch of 256: a multiple of the workers
])
def test_tasks_are_split_among_workers_only_when_each_gets_a_large_batch(tasks, workers, batches):
    ex = _Recorder(workers)
    out = ev.evaluate(ex, list(range(tasks)), batch_size=256)
    assert ex.batches == [batches]
    assert out == list(range(tasks))  # in task order


def test_recordings_ride_in_the_first_batch_and_move_no_bit(tmp_path):
    """evaluate's ``recordings`` and record(): runs recorded as extra rows of one batch write
    the files their runs alone write, and the tasks' results are those of the batch without
    them."""
    import dataclasses

    from rocas.rollout import simulate
    from rocas.scenarios import load_example
    from rocas.search import SerialExecutor

    s = dataclasses.replace(load_example("roundabout_red_truck"), duration_s=6.0)
    tasks = [ev.VariantTask(s, (), 3), ev.VariantTask(s, (("planning.cruise_speed_mps", 9.0),), 4)]
    fixed = ev.VariantTask(s, (("perception.brake_threshold", 0.9),), s.seed)
    alone = tmp_path / "alone.mcap"
    simulate(s, dict(fixed.params), fixed.seed, output=alone)

    got = ev.evaluate(SerialExecutor(), tasks, recordings=[(fixed, tmp_path / "fixed.mcap")])
    want = ev.run_batch(tasks)
    for g, w in zip(got, want, strict=True):
        assert g.outcome == w.outcome
        assert np.array_equal(g.ego_xy, w.ego_xy) and np.array_equal(g.actors_xy, w.actors_xy)
    assert (tmp_path / "fixed.mcap").read_bytes() == alone.read_bytes()

    # several recordings in one batch, and none lost when there are no tasks to ride with
    assert ev.evaluate(SerialExecutor(), [], recordings=[(fixed, tmp_path / "again.mcap")]) == []
    assert (tmp_path / "again.mcap").read_bytes() == alone.read_bytes()
    ev.record([(tasks[0], tmp_path / "t0.mcap"), (fixed, tmp_path / "f.mcap")])
    simulate(s, None, 3, output=tmp_path / "t0_alone.mcap")
    assert (tmp_path / "t0.mcap").read_bytes() == (tmp_path / "t0_alone.mcap").read_bytes()
    assert (tmp_path / "f.mcap").read_bytes() == alone.read_bytes()
