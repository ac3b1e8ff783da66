"""What replay reads from a ``lav`` recording: the ego from ``/lav/gnss/ego`` and every other
agent from ``/lav/pnp/agents`` (world coordinates already; map objects are left out, the world
attachment holds them)."""

from __future__ import annotations

import math
from typing import Any

from rocas.stacks.base import AgentRow, PoseRow
from rocas.stacks.lav.topics import TOPIC_AGENTS, TOPIC_EGO

_NS = 1e-9


def read_motion(recording: Any) -> tuple[list[PoseRow], list[AgentRow]]:
    """One pass over the two channels of an open :class:`rocas.recording.reader.Recording`."""
    poses: list[PoseRow] = []
    agents: list[AgentRow] = []
    for m in recording.decoded({TOPIC_EGO, TOPIC_AGENTS}):
        t = m.log_time_ns * _NS
        msg = m.message
        if m.channel.topic == TOPIC_EGO:
            poses.append((t, msg.position.x, msg.position.y, msg.heading_rad, msg.speed_mps,
                          msg.accel_mps2))
            continue
        for g in msg.agents:
            if g.kind == "static" or g.kind not in ("vehicle", "bicycle", "pedestrian"):
                continue
            agents.append((t, int(g.id), g.position.x, g.position.y, g.heading_rad,
                           g.speed_mps * math.cos(g.heading_rad),
                           g.speed_mps * math.sin(g.heading_rad), g.length_m, g.width_m,
                           g.height_m, g.kind, g.color or "unknown"))
    return poses, agents
