"""The contract between the simulator and a system under test (a *stack*).

Each simulation step the rollout hands a stack an :class:`Observation` (the world as sensors
would see it: ego and actor states, the step's time) and gets back an :class:`Actuation`
(demanded acceleration and path curvature, estop, and whether the stack's own plan gives a
traffic reason to stand still). A stack declares its parameters (:class:`ParamSpec`: name,
module, default, range, unit) and its channels (:class:`ChannelSpec`: topic, message type,
writer, readers, period, role); the channels are its topology in a recording.

All arrays carry a leading batch axis N (variants simulated together); variant i's result never
depends on another variant.
"""

from __future__ import annotations

import functools
from collections.abc import Iterator, Mapping, Sequence
from dataclasses import dataclass
from typing import Any, Protocol, runtime_checkable

import numpy as np

from rocas.errors import ScenarioError

# what a recording carries besides the channels: one definition, the recording layer's
from rocas.recording.topology import (  # noqa: F401
    EGO_METADATA,
    RUN_METADATA,
    STACK_METADATA,
    WORLD_ATTACHMENT,
)

# what a stack receives and returns each step is the simulator's contract, one definition
from rocas.sim.protocol import Actuation, MessageSink, Observation, StackRun  # noqa: F401


@dataclass(frozen=True)
class ParamSpec:
    """One named parameter of a stack.

    Attributes:
        module: the module that reads it.
        name: name within the module.
        default: default value.
        low, high: inclusive range a search may explore.
        unit: SI unit ("" dimensionless, "bool" 0/1, "enum" a choice, "frames" a count).
        description: one line.
    """

    module: str
    name: str
    default: float
    low: float
    high: float
    unit: str
    description: str

    @property
    def full_name(self) -> str:
        return f"{self.module}.{self.name}"

    @property
    def is_integer(self) -> bool:
        return self.unit in ("bool", "enum", "frames")


@dataclass(frozen=True)
class ChannelSpec:
    """A channel a stack publishes: who writes it, who reads it, how often.

    Attributes:
        topic: channel name.
        message_type: generated protobuf class.
        writer: module that publishes it.
        readers: modules that subscribe to it.
        period_s: publishing period [s].
        role: "control" on the one channel Algorithm 1 starts from, else None.
    """

    topic: str
    message_type: type[Any]
    writer: str
    readers: tuple[str, ...]
    period_s: float
    role: str | None = None


#: replay's view of the ego at one time: (t [s], x [m], y [m], yaw [rad], speed [m/s],
#: longitudinal acceleration [m/s^2])
PoseRow = tuple[float, float, float, float, float, float]
#: one perceived agent at one time, world frame: (t [s], track id, x, y [m], heading [rad],
#: vx, vy [m/s], length, width, height [m], kind ("vehicle", "bicycle", "pedestrian"), colour)
AgentRow = tuple[float, int, float, float, float, float, float, float, float, float, str, str]


@runtime_checkable
class Stack(Protocol):
    """A system under test, registered by name (:mod:`rocas.stacks.registry`)."""

    name: str
    modules: tuple[str, ...]
    parameters: tuple[ParamSpec, ...]
    channels: tuple[ChannelSpec, ...]

    def build(self, world: Any, params: Mapping[str, np.ndarray]) -> StackRun:
        """A run for the compiled world (``rocas.sim.world.BatchWorld``, N variants) with
        every parameter as an (N,) array (:func:`batch_params`)."""
        ...


@dataclass(frozen=True)
class AlphaBetaTracker:
    """A stack's obstacle tracker, when it is an alpha-beta filter publishing its state.

    Each frame it predicts ``p = x + v dt`` and, on a measurement ``z``, publishes
    ``x = p + position_gain (z - p)`` and ``v = v + velocity_gain (z - p) / dt``; a missed
    frame is coasted (``x = p``, ``v`` unchanged). Replay undoes it (the published positions
    lag an accelerating obstacle and a new track, whose velocity starts from rest).

    Attributes:
        position_gain: share of the innovation applied to the position (0, 1].
        velocity_gain: share applied to the velocity, per frame (0, 1].
        hidden_frames: frames a new track is updated before it is first published (the
            track's velocity starts from rest at the first); only 0 and 1 can be undone.
    """

    position_gain: float
    velocity_gain: float
    hidden_frames: int = 1


#: What a stack may declare besides the protocol (read with ``getattr``; never its name):
#:
#: - ``read_motion(recording) -> (list[PoseRow], list[AgentRow])``: its own ego and perception
#:   channels read from an open :class:`rocas.recording.reader.Recording` (one pass), for
#:   replaying a recording that lacks rocas's standard pose and obstacle channels;
#: - ``tracker(params) -> AlphaBetaTracker | None``: its obstacle tracker with the parameters in
#:   force (a mapping of full names to values), which replay undoes;
#: - ``braking_limits`` / ``sensing_limits``: parameter names the cyber search must not lower
#:   (a "fix" that brakes or senses less only hides the accident), ``pace_limits``: names it
#:   must not raise (a "fix" that drives faster wins a race);
#: - ``substitutable``: modules whose output it can replace by ground truth (module
#:   substitution; ``build`` then takes ``oracle_modules``), which the confidence phase's
#:   second opinion uses;
#: - ``records_rows``: its runs publish any row of a batch (``publish(..., variant=i)``), so a
#:   batch records several rows in one pass;
#: - ``catalog``: the folder of :mod:`rocas.catalog` holding its accident catalog;
#:   ``recordings``: the subfolder of the repository's ``recordings/`` with its catalog's
#:   recordings (default: its name); ``variant_families``: its catalog takes
#:   :mod:`rocas.catalog.variants`' families (``rocas catalog generate --family``);
#: - ``world``: the name of another simulator's world it drives in (highway-env's for the
#:   ``highway`` stack); such a stack has its own rollout, and :mod:`rocas.rollout` refuses it;
#: - ``analyze_recording(path, out, *, seed, workers, executor) -> report``: its own analysis
#:   of one of its recordings (a stack of another world analyses there), which ``rocas
#:   analyze`` runs instead of rocas's pipeline; the report has ``to_json()`` (``--json``) and
#:   ``lines()`` (the terminal);
#: - ``bench(ids, seeds, *, workers, executor, progress) -> dict``: its own catalog analysed
#:   and scored once per seed, its simulations on the executor named (``rocas bench
#:   --executor``, :func:`rocas.search.executor.make_executor`), in the rows
#:   :func:`rocas.pipeline.bench.run_bench_seeds` returns (each with ``timings_s`` and
#:   ``simulations`` per phase), which ``rocas bench --stack NAME`` prints as it prints the
#:   built-in bench;
#: - ``catalog_entries() -> list[dict]`` and ``record_catalog(ids, directory) -> Iterator[dict]``:
#:   its own accident catalog, for a stack of another world (no ``catalog`` folder):
#:   ``rocas catalog list`` prints the rows (``id``, ``key``, ``title``, ``world``, ``module``,
#:   ``parameters``, ``fix`` {parameter: value}, ``fixable``; ``--json`` all of them), and
#:   ``rocas catalog record DIR [--only ID]`` writes each entry's accident recording in its
#:   world, one row per file as it is written (``id``, ``path``, ``outcome`` text,
#:   ``documented``: it ends in the entry's accident); ``generate`` refuses such a catalog.
CAPABILITIES = ("read_motion", "tracker", "braking_limits", "sensing_limits", "pace_limits",
                "substitutable", "records_rows", "catalog", "recordings", "variant_families",
                "world", "analyze_recording", "bench", "catalog_entries", "record_catalog")


@runtime_checkable
class SelfSimulating(Protocol):
    """A stack that runs its own simulator (an external command) instead of being built into
    rocas's world: the rollout hands it whole scenarios."""

    name: str
    parameters: tuple[ParamSpec, ...]

    def simulate_one(self, scenario: Any, params: StackParams, seed: int | None, *,
                     output: Any = None) -> Any:
        """One run (a :class:`rocas.sim.engine.RunResult`), recorded to ``output`` if given."""
        ...

    def simulate_batch(self, scenarios: Sequence[Any], params: Sequence[StackParams],
                       seeds: Sequence[int]) -> Any:
        """N runs (a :class:`rocas.sim.engine.BatchResult`)."""
        ...


class StackParams(Mapping[str, float]):
    """A full, validated, hashable, picklable assignment of one stack's parameters: the
    stack's defaults with overrides on top (the one parameter API of every stack)."""

    __slots__ = ("_index", "_specs", "_values")

    def __init__(self, specs: Sequence[ParamSpec], overrides: Mapping[str, float] | None = None,
                 *, source: str = "overrides") -> None:
        self._specs = tuple(specs)
        self._index = _index_of(self._specs)
        values = {p.full_name: float(p.default) for p in self._specs}
        for name, value in (overrides or {}).items():
            values[name] = validate_value(self._index, name, value, source=source)
        self._values = tuple(values[p.full_name] for p in self._specs)

    def __getitem__(self, name: str) -> float:
        try:
            return self._values[_positions(self._specs)[name]]
        except KeyError:
            raise KeyError(name) from None

    def __iter__(self) -> Iterator[str]:
        return (p.full_name for p in self._specs)

    def __len__(self) -> int:
        return len(self._values)

    def __hash__(self) -> int:
        return hash(self._values)

    def __eq__(self, other: object) -> bool:
        return isinstance(other, StackParams) and other._values == self._values \
            and other._specs == self._specs

    def __reduce__(self) -> tuple[object, tuple[object, ...]]:
        return (StackParams, (self._specs, self.overrides()))

    @property
    def specs(self) -> tuple[ParamSpec, ...]:
        return self._specs

    def overrides(self) -> dict[str, float]:
        """Only the values that differ from the defaults."""
        return {p.full_name: v for p, v in zip(self._specs, self._values, strict=True)
                if v != p.default}

    def with_values(self, changes: Mapping[str, float]) -> StackParams:
        """A copy with ``changes`` (full names) on top."""
        return StackParams(self._specs, {**self.overrides(), **changes})

    def as_array(self) -> np.ndarray:
        """Values in inventory order, shape (P,)."""
        return np.asarray(self._values, dtype=np.float64)


@functools.cache
def _index_of(specs: tuple[ParamSpec, ...]) -> dict[str, ParamSpec]:
    return {p.full_name: p for p in specs}


@functools.cache
def _positions(specs: tuple[ParamSpec, ...]) -> dict[str, int]:
    return {p.full_name: i for i, p in enumerate(specs)}


def validate_value(index: Mapping[str, ParamSpec], name: str, value: object, *,
                   source: str = "overrides") -> float:
    """Check one parameter name and value against a stack's inventory."""
    p = index.get(name)
    if p is None:
        close = [n for n in index if n.split(".")[-1] == name.split(".")[-1]]
        hint = f"did you mean {close[0]}?" if close else "see 'rocas params --stack NAME'"
        raise ScenarioError(f"{source}: {name}: unknown parameter of this stack", hint)
    if isinstance(value, bool):
        value = float(value)
    try:
        v = float(value)  # type: ignore[arg-type]
    except (TypeError, ValueError):
        raise ScenarioError(f"{source}: {name}: expected a number, got {value!r}") from None
    if not p.low <= v <= p.high:
        raise ScenarioError(f"{source}: {name}: {v:g} is out of range [{p.low:g}, {p.high:g}] "
                            f"{p.unit}".rstrip())
    if p.is_integer and v != round(v):
        raise ScenarioError(f"{source}: {name}: expected an integer, got {v:g}")
    return v


def batch_params(sets: Sequence[StackParams]) -> dict[str, np.ndarray]:
    """N assignments of one stack -> ``{name: (N,) float64}``, what a stack's modules read."""
    if not sets:
        return {}
    table = np.stack([s.as_array() for s in sets])
    return {name: np.ascontiguousarray(table[:, i]) for i, name in enumerate(sets[0])}


def parse_assignment(text: str, specs: Sequence[ParamSpec]) -> tuple[str, float]:
    """``module.param=value`` (as given to ``--set``), checked against a stack's inventory."""
    name, sep, raw = text.partition("=")
    name, raw = name.strip(), raw.strip().lower()
    if not sep or not name or not raw:
        raise ScenarioError(f"--set {text}: expected module.param=value")
    if raw in ("true", "false"):
        value = float(raw == "true")
    else:
        try:
            value = float(raw)
        except ValueError:
            raise ScenarioError(f"--set {text}: {raw!r} is not a number") from None
    return name, validate_value(_index_of(tuple(specs)), name, value, source="--set")
