"""How evaluate groups simulations into batches and batches onto workers."""

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
