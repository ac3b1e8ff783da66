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

from collections.abc import Iterator, Mapping, Sequence
from dataclasses import dataclass
from typing import Any, Protocol, runtime_checkable

import numpy as np

from rocas.errors import ScenarioError

# what a stack receives and returns each step is the simulator's contract, one definition
from rocas.sim.protocol import Actuation, MessageSink, Observation, StackRun  # noqa: F401

#: recording attachment holding the static world (the scenario format without actors)
WORLD_ATTACHMENT = "rocas/world.json"
#: recording metadata record naming the stack that made the recording
STACK_METADATA = "rocas.stack"
EGO_METADATA = "rocas.ego"
RUN_METADATA = "rocas.run"


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


#: Optional, for ``rocas analyze`` on a stack's recordings: a stack may define
#: ``read_motion(recording) -> (list[PoseRow], list[AgentRow])`` reading its own ego and
#: perception channels from an open :class:`rocas.recording.reader.Recording` (one pass);
#: ``tracker(params) -> AlphaBetaTracker | None``, its obstacle tracker with the parameters
#: in force (a mapping of full names to values), which replay undoes;
#: ``braking_limits`` / ``sensing_limits`` (parameter names) that the cyber search must not
#: lower (a "fix" that brakes or senses less only hides the accident); and ``pace_limits`` that
#: it must not raise (a "fix" that drives faster wins a race).


class StackParams(Mapping[str, float]):
    """A full, validated, hashable, picklable assignment of one stack's parameters."""

    __slots__ = ("_specs", "_values")

    def __init__(self, specs: Sequence[ParamSpec], overrides: Mapping[str, float] | None = None,
                 *, source: str = "overrides") -> None:
        self._specs = tuple(specs)
        index = {p.full_name: p for p in self._specs}
        values = {p.full_name: float(p.default) for p in self._specs}
        for name, value in (overrides or {}).items():
            values[name] = validate_value(index, name, value, source=source)
        self._values = tuple(values[p.full_name] for p in self._specs)

    def __getitem__(self, name: str) -> float:
        for p, v in zip(self._specs, self._values, strict=True):
            if p.full_name == name:
                return v
        raise KeyError(name)

    def __iter__(self) -> Iterator[str]:
        return (p.full_name for p in self._specs)

    def __len__(self) -> int:
        return len(self._values)

    def __hash__(self) -> int:
        return hash(self._values)

    def __eq__(self, other: object) -> bool:
        return isinstance(other, StackParams) and other._values == self._values \
            and other._specs == self._specs

    def overrides(self) -> dict[str, float]:
        """Only the values that differ from the defaults."""
        return {p.full_name: v for p, v in zip(self._specs, self._values, strict=True)
                if v != p.default}


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
    """N assignments -> ``{name: (N,) float64}``, what a stack's modules read."""
    if not sets:
        return {}
    names = list(sets[0])
    return {n: np.array([s[n] for s in sets], dtype=np.float64) for n in names}
