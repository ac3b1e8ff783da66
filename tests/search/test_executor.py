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


def test_an_interruption_ends_the_workers_without_waiting_for_their_tasks(tmp_path):
    # SIGINT to this process only (as kill -INT PID or a job scheduler sends it): the workers
    # do not see it; the tasks under way (30 s each) are dropped, not waited for
    tasks = [(str(tmp_path), i, 0.05 if i < 2 else 30.0) for i in range(40)]

    def interrupt_after_two_tasks():
        _wait_for(lambda: len(os.listdir(tmp_path)) >= 2)
        time.sleep(0.2)  # the next two tasks are under way
        os.kill(os.getpid(), signal.SIGINT)

    threading.Thread(target=interrupt_after_two_tasks, daemon=True).start()
    pool = LocalExecutor(workers=2)
    start = time.monotonic()
    with pytest.raises(KeyboardInterrupt), pool:
        pool.map(executor_tasks.slow_touch, tasks)
    assert time.monotonic() - start < 20.0  # waiting for a task under way takes 30 s
    assert sorted(os.listdir(tmp_path)) == ["task-0", "task-1"]
    assert pool.map(executor_tasks.slow_touch, tasks[:2]) == [0, 1]  # usable again, new workers
    pool.close()


def _gone(pid: int) -> bool:
    """The process has exited (an orphan adopted by a PID 1 that does not reap stays a zombie)."""
    try:
        with open(f"/proc/{pid}/stat") as f:
            return f.read().rsplit(")", 1)[1].split()[0] == "Z"
    except FileNotFoundError:
        return True


@pytest.mark.skipif(not os.path.isdir("/proc/self"), reason="reads /proc")
def test_workers_exit_when_the_main_process_is_killed(tmp_path):
    import subprocess
    import sys
    from pathlib import Path

    import rocas

    script = ("import executor_tasks, sys\n"
              "from rocas.search import LocalExecutor\n"
              "if __name__ == '__main__':\n"
              "    with LocalExecutor(workers=2) as pool:\n"
              "        pool.map(executor_tasks.note_pid_and_sleep, [(sys.argv[1], 0.5)] * 100)\n")
    paths = [str(Path(rocas.__file__).parents[1]), str(Path(executor_tasks.__file__).parent)]
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(paths))
    main = subprocess.Popen([sys.executable, "-c", script, str(tmp_path)], env=env,
                            stderr=subprocess.PIPE, text=True)
    try:
        _wait_for(lambda: len(os.listdir(tmp_path)) >= 2)
    finally:
        main.kill()
        main.wait()
    workers = [int(name.removeprefix("pid-")) for name in os.listdir(tmp_path)]
    # each worker was in the middle of a 0.5 s task (and had 50 to go in its share before)
    _wait_for(lambda: all(_gone(pid) for pid in workers), timeout_s=3.0)
    # the pipe closes once the resource tracker, which shares it, has cleaned up and exited
    _, err = main.communicate(timeout=30)
    assert "leaked" not in err and "Warning" not in err, err


def test_a_worker_starts_watching_its_parent_before_any_heavy_import():
    # a spawned worker imports its initializer's module before it runs it, and the tasks'
    # modules only after: a parent killed while its workers start is seen at once
    import subprocess
    import sys

    code = ("import sys, rocas._worker\n"
            "print(' '.join(m for m in ('rocas.search', 'numpy') if m in sys.modules))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True, timeout=60).stdout
    assert out.strip() == ""


def test_submit_runs_a_task_on_a_worker_without_waiting_and_warm_up_starts_them():
    from rocas.search.executor import submit

    with LocalExecutor(workers=2) as pool:
        pool.warm_up(executor_tasks.pid_of_worker)
        assert len(pool._get_pool()._processes) == 2  # started before any map or submit
        job = submit(pool, executor_tasks.pid_of_worker)
        assert job.result(timeout=60) != os.getpid()
        with pytest.raises(ValueError, match="boom"):
            submit(pool, executor_tasks.fail, "boom").result(timeout=60)
    # with one worker, or an executor that cannot submit, the task runs here at once
    assert LocalExecutor(workers=1).submit(executor_tasks.pid_of_worker).result() == os.getpid()
    serial = submit(SerialExecutor(), executor_tasks.pid_of_worker)
    assert serial.done() and serial.result() == os.getpid()
    with pytest.raises(ValueError, match="here"):
        submit(SerialExecutor(), executor_tasks.fail, "here").result()


def test_abort_ends_the_workers_without_waiting_for_a_submitted_task(tmp_path):
    pool = LocalExecutor(workers=2)
    job = pool.submit(executor_tasks.note_pid_and_sleep, (str(tmp_path), 60.0))
    _wait_for(lambda: list(tmp_path.glob("pid-*")))
    start = time.monotonic()
    pool.abort()
    assert time.monotonic() - start < 10  # not the task's 60 s
    pid = int(next(tmp_path.glob("pid-*")).name.split("-")[1])
    _wait_for(lambda: not os.path.exists(f"/proc/{pid}"))
    assert job.done()
    pool.close()  # nothing left to close
