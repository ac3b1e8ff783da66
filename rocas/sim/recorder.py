"""Recording mode: one run of any stack to an MCAP file.

The file carries the stack's channels with their topology (``rocas.writers``, ``rocas.readers``,
``rocas.role``), the static world as the ``rocas/world.json`` attachment, the ego mission and
the stack's parameter overrides as the ``rocas.ego`` metadata record and the run's outcome as
``rocas.run``: one file is enough to replay. The messages are the stack's: it builds them and
hands them to :meth:`RunRecorder.write` (the engine's message sink).
"""

from __future__ import annotations

import json
import os
from collections.abc import Mapping, Sequence
from types import TracebackType

from rocas.recording.topology import (
    EGO_METADATA,
    RUN_METADATA,
    STACK_METADATA,
    WORLD_ATTACHMENT,
)
from rocas.recording.writer import RecordingWriter
from rocas.scenarios.loader import scenario_to_dict, world_to_dict
from rocas.scenarios.model import Scenario
from rocas.sim.oracles import Outcome
from rocas.sim.protocol import Channel


class RunRecorder:
    """Context manager that writes one run; use :meth:`write` as the engine's message sink and
    :meth:`finish` with the outcome before closing.

    Args:
        path: the MCAP file to write (atomically).
        scenario: the scenario simulated.
        channels: the stack's channels, registered in this order.
        param_overrides: the stack's parameters that differ from its defaults.
        seed: the run's seed.
        stack_name: the registered stack that made the run (the ``rocas.stack`` record).
    """

    def __init__(self, path: str | os.PathLike[str], scenario: Scenario,
                 channels: Sequence[Channel], param_overrides: Mapping[str, float],
                 seed: int, stack_name: str | None = None) -> None:
        self.writer = RecordingWriter(path)
        self.count = 0
        for ch in channels:
            self.writer.add_channel(ch.topic, ch.message_type, writers=[ch.writer],
                                    readers=list(ch.readers), role=ch.role,
                                    metadata={"rocas.period_s": f"{ch.period_s:g}"})
        self.writer.add_attachment(WORLD_ATTACHMENT,
                                   json.dumps(world_to_dict(scenario), indent=1).encode(),
                                   media_type="application/json")
        ego = scenario_to_dict(scenario)["ego"]
        self.writer.add_metadata(EGO_METADATA, {
            "scenario": scenario.name,
            "route": ",".join(scenario.ego.route),
            "start_s_m": repr(scenario.ego.start_s_m),
            "start_lateral_m": repr(scenario.ego.start_lateral_m),
            "start_speed_mps": repr(scenario.ego.start_speed_mps),
            "destination_s_m": "" if scenario.ego.destination_s_m is None
            else repr(scenario.ego.destination_s_m),
            "params": json.dumps(dict(param_overrides), sort_keys=True),
            "seed": str(seed),
            "dt_s": repr(scenario.dt_s),
            "duration_s": repr(scenario.duration_s),
            "ego": json.dumps(ego, sort_keys=True),
            "actors": json.dumps(scenario_to_dict(scenario)["actors"]),
        })
        if stack_name is not None:
            self.writer.add_metadata(STACK_METADATA, {"name": stack_name})

    # -- context manager ------------------------------------------------------------------
    def __enter__(self) -> RunRecorder:
        return self

    def __exit__(self, exc_type: type[BaseException] | None, exc: BaseException | None,
                 tb: TracebackType | None) -> None:
        self.writer.__exit__(exc_type, exc, tb)

    def write(self, topic: str, msg: object, t_ns: int) -> None:
        """Write one message at log time ``t_ns`` [ns] (a :data:`MessageSink`)."""
        self.writer.write(topic, msg, log_time_ns=t_ns)
        self.count += 1

    def finish(self, outcome: Outcome) -> None:
        """Write the run's outcome (the ``rocas.run`` record)."""
        self.writer.add_metadata(RUN_METADATA, outcome_metadata(outcome))


def outcome_metadata(outcome: Outcome) -> dict[str, str]:
    """The ``rocas.run`` record of a run: what happened, as strings."""
    return {
        "outcome": outcome.summary(),
        "collided": str(outcome.collided).lower(),
        "collision_with": outcome.collision_with or "",
        "collision_time_s": _opt(outcome.collision_time_s),
        "collision_kind": outcome.collision_kind or "",
        "collision_position": "" if outcome.collision_position is None
        else json.dumps([float(v) for v in outcome.collision_position]),
        "emergency": str(outcome.emergency).lower(),
        "hard_brake_time_s": _opt(outcome.hard_brake_time_s),
        "estop_time_s": _opt(outcome.estop_time_s),
        "unexpected_stop": str(outcome.unexpected_stop).lower(),
        "max_decel_mps2": repr(outcome.max_decel_mps2),
        "min_separation_m": repr(outcome.min_separation_m),
        "route_completion": repr(outcome.route_completion),
    }


def _opt(v: float | None) -> str:
    """A metadata value for an optional time: "" when absent."""
    return "" if v is None else repr(float(v))
