"""What the simulator asks of a system under test, per step.

The simulator knows worlds, not stacks: the engine (:mod:`rocas.sim.engine`) is given a
:data:`StackFactory`, which builds a :class:`StackRun` for a compiled world, and each step hands
that run an :class:`Observation` and applies the :class:`Actuation` it returns. Whatever a stack
is made of (modules, channels, parameters) stays on its side; the oracles read only the
actuation (estop, and whether the stack names a traffic reason to stand still).

All arrays carry a leading batch axis N (variants simulated together); variant i's result never
depends on another variant.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Protocol, runtime_checkable

import numpy as np

if TYPE_CHECKING:
    from rocas.sim.world import BatchWorld


@dataclass(frozen=True, eq=False)
class Observation:
    """What a stack receives each step (N variants, A actors).

    Attributes:
        tick: step index; t_s: its time [s].
        ego_x, ego_y, ego_yaw, ego_speed, ego_accel: (N,) ego state [m, m, rad, m/s, m/s^2].
        actor_x, actor_y, actor_yaw, actor_speed: (N, A) actor bodies [m, m, rad, m/s].
        detail: the simulator's own state objects: ``ego`` (:class:`VehicleState`),
            ``actors`` (the actors' bodies, :class:`VehicleState`) and ``actor_state``
            (:class:`rocas.sim.actors.ActorState`), for stacks that need more than the above
            (ground-truth substitutes that roll the actors forward).
    """

    tick: int
    t_s: float
    ego_x: np.ndarray
    ego_y: np.ndarray
    ego_yaw: np.ndarray
    ego_speed: np.ndarray
    ego_accel: np.ndarray
    actor_x: np.ndarray
    actor_y: np.ndarray
    actor_yaw: np.ndarray
    actor_speed: np.ndarray
    detail: Mapping[str, Any]


@dataclass(frozen=True, eq=False)
class Actuation:
    """What a stack returns each step, all (N,).

    Attributes:
        accel_mps2: demanded longitudinal acceleration [m/s^2] (negative brakes).
        curvature_1pm: demanded path curvature [1/m] (positive turns left).
        estop: the stack raised an emergency stop.
        stop_justified: the stack's own plan names a traffic reason to stand (a red light, a
            vehicle ahead); standing still >= 2 s without one is an unexpected stop.
    """

    accel_mps2: np.ndarray
    curvature_1pm: np.ndarray
    estop: np.ndarray
    stop_justified: np.ndarray


#: (topic, message, log time [ns]) -> None: where a stack writes its messages in recording mode
MessageSink = Callable[[str, Any, int], None]


@runtime_checkable
class StackRun(Protocol):
    """One stack instance driving N variants through one run."""

    def step(self, obs: Observation) -> Actuation:
        """Decide this step's actuation."""
        ...

    def publish(self, sink: MessageSink, tick: int, t_ns: int) -> None:
        """Write variant 0's messages of the last step (recording mode only). A stack that can
        record other rows of a batch too (the built-in ADS) takes ``variant=i`` as well:
        :func:`rocas.sim.engine.rollout` with ``sinks``."""
        ...

    def digest(self) -> dict[str, np.ndarray]:
        """Per module, an (N,) fingerprint of what it published in the last step (modules
        that did not run this step are absent); summed over a run it shows whether a
        parameter changed a module's output."""
        ...


#: builds a stack's run for a compiled world of N variants
StackFactory = Callable[["BatchWorld"], StackRun]


class Channel(Protocol):
    """A channel a stack publishes, as the recorder writes it (topology and period)."""

    @property
    def topic(self) -> str: ...
    @property
    def message_type(self) -> type[Any]: ...
    @property
    def writer(self) -> str: ...
    @property
    def readers(self) -> tuple[str, ...]: ...
    @property
    def period_s(self) -> float: ...
    @property
    def role(self) -> str | None: ...
