"""The local process pool: results in task order, prompt interruption, no orphaned workers."""

import os
import signal
import threading
import time

import executor_tasks
import pytest

from rocas.search import LocalExecutor, SerialExecutor


def _wait_for(condition, timeout_s=60.0):
    end = time.monotonic() + timeout_s
    while not condition():
        if time.monotonic() > end:
            raise AssertionError("timed out")
        time.sleep(0.01)


def test_results_come_back_in_task_order(tmp_path):
    tasks = [(str(tmp_path), i, 0.01 * (i % 3)) for i in range(11)]
    with LocalExecutor(workers=2) as pool:
        assert pool.map(executor_tasks.slow_touch, tasks) == list(range(11))
    assert SerialExecutor().map(executor_tasks.slow_touch, tasks) == list(range(11))


def test_an_interruption_waits_for_at_most_one_task_per_worker(tmp_path):
    # SIGINT to this process only (as kill -INT PID or a job scheduler sends it): the workers
    # do not see it, so whatever they were given still runs before the pool closes
    tasks = [(str(tmp_path), i, 0.05) for i in range(40)]

    def interrupt_after_two_tasks():
        _wait_for(lambda: len(os.listdir(tmp_path)) >= 2)
        os.kill(os.getpid(), signal.SIGINT)

    threading.Thread(target=interrupt_after_two_tasks, daemon=True).start()
    with pytest.raises(KeyboardInterrupt), LocalExecutor(workers=2) as pool:
        pool.map(executor_tasks.slow_touch, tasks)
    # two finished, two under way when the signal came, and two given to the workers while it
    # was on its way (the whole list, 40, when each worker got half of it in one piece)
    assert len(os.listdir(tmp_path)) <= 6
