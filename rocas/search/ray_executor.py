"""A Ray executor: the batches of an analysis or a campaign on a Ray cluster.

``rocas analyze --executor ray`` and ``rocas triage --executor ray [--address ADDR]`` run their
simulations here. The pipeline already groups its simulations into batches
(:func:`rocas.pipeline.evaluate.evaluate` calls ``executor.map(run_batch, batches)``), and each
task this executor receives becomes one Ray task: one batch per task, never one individual, so
the simulator's batch mode keeps its throughput on every node (pymoo's own Ray runner sends one
individual per task and loses it). Results come back in task order, and a batch's results depend
only on its tasks, so the same seed gives the same report as the local executor.

Ray is an optional dependency (``pip install rocas[ray]``), imported only when this executor is
built. Without an address (and without ``RAY_ADDRESS`` in the environment) a private local Ray
is started with ``workers`` CPUs (default: all cores) and shut down again by :meth:`close`; with
one, the executor joins that cluster and leaves it running. A Ray already initialised in this
process (a test session's, a notebook's) is used as it is and left running.
"""

from __future__ import annotations

import os
from collections.abc import Callable, Sequence
from typing import Any, TypeVar

from rocas.errors import RocasError, UsageError

T = TypeVar("T")
R = TypeVar("R")

#: shared memory a private local Ray reserves for its object store [bytes]: batches and their
#: trajectories are a few MB, far below Ray's default (30 % of the machine's memory)
LOCAL_OBJECT_STORE_BYTES = 256 * 1024 * 1024


def _import_ray() -> Any:
    try:
        import ray
    except ImportError:
        raise UsageError("the ray executor needs Ray, which is not installed",
                         "pip install 'rocas[ray]', or use --executor local") from None
    return ray


class RayExecutor:
    """Maps a picklable function over tasks as one Ray task each (see the module docstring).

    Attributes:
        workers: CPUs of the cluster (what the pipeline sizes its batches by).
        address: the cluster's address, or None for a local Ray.
    """

    name = "ray"

    def __init__(self, workers: int | None = None, address: str | None = None) -> None:
        if workers is not None and workers < 1:
            raise UsageError(f"--workers must be at least 1, got {workers}")
        ray = _import_ray()
        self._ray = ray
        self.address = address or os.environ.get("RAY_ADDRESS") or None
        self._owned = False
        if not ray.is_initialized():
            kwargs: dict[str, Any] = {"include_dashboard": False, "log_to_driver": False,
                                      "configure_logging": False}
            if self.address is None:  # a private local Ray sized like the local executor
                kwargs.update(num_cpus=workers or os.cpu_count() or 1,
                              object_store_memory=LOCAL_OBJECT_STORE_BYTES)
            try:
                ray.init(address=self.address, **kwargs)
            except (ConnectionError, RuntimeError, ValueError) as exc:
                where = self.address or "a local Ray"
                raise RocasError(f"cannot start or join {where}: {str(exc).splitlines()[0]}",
                                 "check --address (e.g. ray://HEAD:10001 or HEAD:6379) and "
                                 "that the cluster is up") from None
            self._owned = True
        cpus = int(ray.cluster_resources().get("CPU", 1))
        self.workers = max(1, min(cpus, workers) if workers else cpus)
        self._remote: dict[Callable[..., Any], Any] = {}

    def map(self, fn: Callable[[T], R], tasks: Sequence[T]) -> list[R]:
        """``[fn(t) for t in tasks]``: one Ray task per element (a batch), results in order.
        An interruption or an error cancels the tasks still under way."""
        tasks = list(tasks)
        if not tasks:
            return []
        remote = self._remote.get(fn)
        if remote is None:
            remote = self._remote[fn] = self._ray.remote(num_cpus=1, max_retries=0)(fn)
        refs = [remote.remote(t) for t in tasks]
        try:
            return list(self._ray.get(refs))
        except BaseException:
            for ref in refs:
                try:
                    self._ray.cancel(ref, force=True)
                except Exception:  # noqa: BLE001 - a finished task cannot be cancelled
                    pass
            raise

    def close(self) -> None:
        """Shut a Ray down that this executor started; a joined or shared one is left."""
        if self._owned and self._ray.is_initialized():
            self._ray.shutdown()
        self._owned = False

    def __enter__(self) -> RayExecutor:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()
