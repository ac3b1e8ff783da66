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

The private local Ray listens on loopback only and, where the installed Ray offers it (2.52 and
later), demands its token (``RAY_AUTH_MODE=token``; Ray keeps the token in ``~/.ray/auth_token``):
its GCS, raylet and workers run whatever they are sent, so no other machine may reach them. Its
dashboard is off. A cluster the user names with ``--address`` is theirs to secure.
"""

from __future__ import annotations

import contextlib
import os
import re
from collections.abc import Callable, Iterator, Sequence
from typing import Any, TypeVar

from rocas.errors import RocasError, UsageError
from rocas.stacks.registry import carrying

T = TypeVar("T")
R = TypeVar("R")

#: shared memory a private local Ray reserves for its object store [bytes]: batches and their
#: trajectories are a few MB, far below Ray's default (30 % of the machine's memory)
LOCAL_OBJECT_STORE_BYTES = 256 * 1024 * 1024

#: the first Ray release with token authentication (``RAY_AUTH_MODE=token``)
TOKEN_AUTH_SINCE = (2, 52)
#: the environment variable that, when false, makes Ray take loopback as the node's address (as
#: it does on macOS and Windows); a node on loopback binds its gRPC servers there
_RAY_CLUSTER_ENV = "RAY_ENABLE_WINDOWS_OR_OSX_CLUSTER"


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
        self._set_auth_mode = False
        if not ray.is_initialized():
            kwargs: dict[str, Any] = {"include_dashboard": False, "log_to_driver": False,
                                      "configure_logging": False}
            private = self.address is None
            if private:  # a private local Ray sized like the local executor
                kwargs.update(num_cpus=workers or os.cpu_count() or 1,
                              object_store_memory=LOCAL_OBJECT_STORE_BYTES)
            if private and "RAY_AUTH_MODE" in private_ray_environment(ray):
                self._set_auth_mode = True  # for as long as this Ray runs (see close)
            try:
                with _private_ray_environment(ray) if private else contextlib.nullcontext():
                    ray.init(address=self.address, **kwargs)
            except (ConnectionError, RuntimeError, ValueError) as exc:
                self.close()
                where = self.address or "a local Ray"
                raise RocasError(f"cannot start or join {where}: {str(exc).splitlines()[0]}",
                                 "check --address (e.g. ray://HEAD:10001 or HEAD:6379) and "
                                 "that the cluster is up") from None
            self._owned = True
        cpus = int(ray.cluster_resources().get("CPU", 1))
        self.workers = max(1, min(cpus, workers) if workers else cpus)
        self._remote: dict[Callable[..., Any], Any] = {}

    @property
    def node_address(self) -> str:
        """The IP address of this process's Ray node (``127.0.0.1`` for a private local Ray)."""
        return str(self._ray.util.get_node_ip_address())

    def map(self, fn: Callable[[T], R], tasks: Sequence[T]) -> list[R]:
        """``[fn(t) for t in tasks]``: one Ray task per element (a batch), results in order.
        An interruption or an error cancels the tasks still under way."""
        tasks = list(tasks)
        if not tasks:
            return []
        carried = carrying(fn)  # the stacks registered here at run time come along
        target = fn if carried is fn else _call
        remote = self._remote.get(target)
        if remote is None:
            remote = self._remote[target] = self._ray.remote(num_cpus=1, max_retries=0)(target)
        refs = [remote.remote(t) if carried is fn else remote.remote(carried, t) for t in tasks]
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
        if self._set_auth_mode:
            os.environ.pop("RAY_AUTH_MODE", None)
            _refresh_ray_config(self._ray)
            self._set_auth_mode = False

    def __enter__(self) -> RayExecutor:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


def _call(fn: Callable[[T], R], task: T) -> R:
    """``fn(task)`` as a Ray task (a :class:`rocas.stacks.registry.Carrying` is no function)."""
    return fn(task)


def ray_version(ray: Any) -> tuple[int, ...]:
    """The installed Ray's version as numbers (``2.60.0`` -> ``(2, 60, 0)``); unknown parts 0."""
    parts = []
    for part in str(getattr(ray, "__version__", "0")).split(".")[:3]:
        digits = re.match(r"\d*", part).group()  # type: ignore[union-attr]
        parts.append(int(digits or 0))
    return tuple(parts)


def private_ray_environment(ray: Any) -> dict[str, str]:
    """The environment a private local Ray is started in: its node on loopback and, where the
    installed Ray offers it, token authentication. A ``RAY_AUTH_MODE`` the user set is kept."""
    env = {_RAY_CLUSTER_ENV: "0"}
    if ray_version(ray) >= TOKEN_AUTH_SINCE and "RAY_AUTH_MODE" not in os.environ:
        env["RAY_AUTH_MODE"] = "token"
    return env


@contextlib.contextmanager
def _private_ray_environment(ray: Any) -> Iterator[None]:
    """While a private Ray starts: :func:`private_ray_environment` in ``os.environ`` (its
    processes inherit it) and in Ray's constant read at import, restored afterwards.

    Ray (on Linux) takes the machine's outward address as the node's and binds its GCS and
    raylet on every interface; with the node on loopback they bind ``127.0.0.1`` only
    (tests/search/test_ray_loopback.py checks the sockets). The token mode stays set while the
    Ray runs: this process's clients read it whenever they connect to the node."""
    env = private_ray_environment(ray)
    saved = {k: os.environ.get(k) for k in env if k != "RAY_AUTH_MODE"}
    os.environ.update(env)
    if "RAY_AUTH_MODE" in env:
        _refresh_ray_config(ray)
    constants = getattr(getattr(ray, "_private", None), "ray_constants", None)
    had = getattr(constants, "ENABLE_RAY_CLUSTER", None)
    if had is not None:
        constants.ENABLE_RAY_CLUSTER = False
    try:
        yield
    finally:
        for k, v in saved.items():
            if v is None:
                os.environ.pop(k, None)
            else:
                os.environ[k] = v
        if had is not None:
            constants.ENABLE_RAY_CLUSTER = had


def _refresh_ray_config(ray: Any) -> None:
    """Make this process's Ray read ``RAY_AUTH_MODE`` again (it caches its configuration at
    import; Ray's own switch to token mode does the same)."""
    config = getattr(getattr(ray, "_raylet", None), "Config", None)
    if config is not None and hasattr(config, "initialize"):
        config.initialize("")
