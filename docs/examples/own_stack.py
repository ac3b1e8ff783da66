"""The worked example of docs/own-stack.md: a small stack that is not rocas's, logging to MCAP.

"ACME" drives behind a lead car: ``perception`` reports the gap, ``planner`` picks a speed,
``controller`` turns it into throttle and brake. Its messages are protobuf types rocas has
never seen (built at run time here; yours come from your own ``.proto`` files), and it logs
with ``mcap_protobuf.writer.Writer`` as many pipelines do.

Run it::

    python docs/examples/own_stack.py OUT_DIR

It writes into OUT_DIR:

- ``reference.mcap`` and ``accident.mcap``: logged the way the pipeline always did (no
  topology); in ``accident.mcap`` the planner's time headway is wrong from t = 3 s on.
- ``acme-cmg.json``: the module graph, for ``--cmg`` and ``rocas annotate``.
- ``attached.mcap``: the accident run logged with the one added call per channel,
  ``rocas.recording.attach_channel``, so it carries the topology itself.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path
from typing import Any

from google.protobuf import descriptor_pb2, descriptor_pool, message_factory
from mcap_protobuf.writer import Writer

from rocas.recording import attach_channel

F = descriptor_pb2.FieldDescriptorProto


def _message_types() -> dict[str, type[Any]]:
    """Build ACME's three message types from a .proto written as a descriptor."""
    fd = descriptor_pb2.FileDescriptorProto(name="acme/av.proto", package="acme.av",
                                            syntax="proto3")

    def message(name: str, *fields: tuple[str, int, int]) -> None:
        m = fd.message_type.add(name=name)
        for number, (field, ftype, label) in enumerate(fields, start=1):
            m.field.add(name=field, number=number, type=ftype, label=label)

    opt = F.LABEL_OPTIONAL
    message("Obstacle", ("gap_m", F.TYPE_DOUBLE, opt), ("speed_mps", F.TYPE_DOUBLE, opt))
    message("SpeedPlan", ("target_speed_mps", F.TYPE_DOUBLE, opt),
            ("headway_s", F.TYPE_DOUBLE, opt))
    message("Command", ("throttle", F.TYPE_DOUBLE, opt), ("brake", F.TYPE_DOUBLE, opt))
    pool = descriptor_pool.DescriptorPool()
    pool.Add(fd)
    return {
        name: message_factory.GetMessageClass(pool.FindMessageTypeByName(f"acme.av.{name}"))
        for name in ("Obstacle", "SpeedPlan", "Command")
    }


TYPES = _message_types()
Obstacle, SpeedPlan, Command = TYPES["Obstacle"], TYPES["SpeedPlan"], TYPES["Command"]

#: ACME's module graph in the --cmg format.
CMG = {
    "modules": {
        "perception": {"reads": [], "writes": ["/acme/obstacle"]},
        "planner": {"reads": ["/acme/obstacle"], "writes": ["/acme/plan"]},
        "controller": {"reads": ["/acme/plan"], "writes": ["/acme/cmd"]},
    },
    "control_channel": "/acme/cmd",
}

DT_S = 0.1  # [s] one cycle of the stack
STEPS = 100  # 10 s
FAULT_AT_S = 3.0  # [s] when the accident run's planner goes wrong


def drive(path: str | Path, *, faulty: bool, attach: bool = False) -> None:
    """Run the stack for 10 s and log every channel with mcap_protobuf's Writer.

    Args:
        path: the MCAP file to write.
        faulty: the planner uses a 0.4 s time headway instead of 2 s from t = 3 s.
        attach: declare each channel's writers/readers with ``attach_channel`` (the only
            lines a pipeline adds to adopt rocas).
    """
    ego_x, ego_v = 0.0, 12.0  # [m], [m/s]
    lead_x, lead_v = 40.0, 8.0  # [m], [m/s]
    plan_in_use = SpeedPlan(target_speed_mps=ego_v, headway_s=2.0)  # one cycle of latency
    with open(path, "wb") as f, Writer(f) as writer:
        if attach:  # --- the rocas lines: once per channel, before the first message ---
            attach_channel(writer, "/acme/obstacle", Obstacle,
                           writers=["perception"], readers=["planner"])
            attach_channel(writer, "/acme/plan", SpeedPlan,
                           writers=["planner"], readers=["controller"])
            attach_channel(writer, "/acme/cmd", Command,
                           writers=["controller"], role="control")
        for step in range(STEPS):
            t_s = step * DT_S
            t_ns = 1_000_000_000 + step * 100_000_000
            obstacle = Obstacle(gap_m=lead_x - ego_x, speed_mps=lead_v)
            writer.write_message("/acme/obstacle", obstacle, log_time=t_ns,
                                 publish_time=t_ns, sequence=step)
            headway_s = 0.4 if faulty and t_s >= FAULT_AT_S else 2.0
            safe_v = max(0.0, (obstacle.gap_m - 5.0) / headway_s)
            plan = SpeedPlan(target_speed_mps=min(15.0, safe_v), headway_s=headway_s)
            writer.write_message("/acme/plan", plan, log_time=t_ns + 1_000_000,
                                 publish_time=t_ns + 1_000_000, sequence=step)
            error = plan_in_use.target_speed_mps - ego_v
            plan_in_use = plan
            cmd = Command(throttle=min(1.0, max(0.0, 0.3 * error)),
                          brake=min(1.0, max(0.0, -0.3 * error)))
            writer.write_message("/acme/cmd", cmd, log_time=t_ns + 2_000_000,
                                 publish_time=t_ns + 2_000_000, sequence=step)
            accel = 3.0 * cmd.throttle - 6.0 * cmd.brake  # [m/s^2]
            ego_v = max(0.0, ego_v + accel * DT_S)
            ego_x += ego_v * DT_S
            lead_x += lead_v * DT_S


def main(out_dir: str | Path) -> dict[str, Path]:
    """Write the example's recordings and CMG file into ``out_dir``; returns their paths."""
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    paths = {
        "reference": out / "reference.mcap",
        "accident": out / "accident.mcap",
        "attached": out / "attached.mcap",
        "cmg": out / "acme-cmg.json",
    }
    drive(paths["reference"], faulty=False)
    drive(paths["accident"], faulty=True)
    drive(paths["attached"], faulty=True, attach=True)
    paths["cmg"].write_text(json.dumps(CMG, indent=2) + "\n", encoding="utf-8")
    return paths


if __name__ == "__main__":
    if len(sys.argv) != 2:
        sys.exit("usage: python docs/examples/own_stack.py OUT_DIR")
    for name, p in main(sys.argv[1]).items():
        print(f"{name:10} {p}")
