"""The topology contract: how a channel says who writes and who reads it.

Channel metadata keys (all optional, values are strings):

- ``rocas.writers``: comma-separated module names that publish on the channel.
- ``rocas.readers``: comma-separated module names that subscribe to it.
- ``rocas.role``: ``control`` marks the channel Algorithm 1 starts from.
- ``callerid``: the ROS 1 profile's publishing node; counts as the writer when
  ``rocas.writers`` is absent.

rocas's own recordings also carry the static world as the ``rocas/world.json`` attachment, the
ego's mission and parameter overrides as the ``rocas.ego`` metadata record and the run's outcome
as ``rocas.run``.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping

WRITERS_KEY = "rocas.writers"
READERS_KEY = "rocas.readers"
ROLE_KEY = "rocas.role"
ROS1_CALLERID_KEY = "callerid"
CONTROL_ROLE = "control"
WORLD_ATTACHMENT = "rocas/world.json"
EGO_METADATA = "rocas.ego"
RUN_METADATA = "rocas.run"
#: metadata record naming the registered stack that made a recording
STACK_METADATA = "rocas.stack"


def split_modules(value: str | None) -> tuple[str, ...]:
    """Parse a comma-separated module list; blanks and duplicates are dropped, order kept."""
    if not value:
        return ()
    seen: dict[str, None] = {}
    for part in value.split(","):
        name = part.strip()
        if name:
            seen.setdefault(name, None)
    return tuple(seen)


def join_modules(modules: Iterable[str]) -> str:
    """Inverse of :func:`split_modules`."""
    return ",".join(split_modules(",".join(modules)))


def topology_metadata(
    writers: Iterable[str] = (), readers: Iterable[str] = (), role: str | None = None
) -> dict[str, str]:
    """Channel metadata entries that declare a channel's writers, readers and role."""
    meta: dict[str, str] = {}
    if w := join_modules(writers):
        meta[WRITERS_KEY] = w
    if r := join_modules(readers):
        meta[READERS_KEY] = r
    if role:
        meta[ROLE_KEY] = role
    return meta


def merge_topology_metadata(
    metadata: Mapping[str, str],
    writers: Iterable[str] = (),
    readers: Iterable[str] = (),
    role: str | None = None,
) -> dict[str, str]:
    """Return a copy of ``metadata`` with the topology keys set (others kept)."""
    merged = {k: v for k, v in metadata.items() if k not in (WRITERS_KEY, READERS_KEY, ROLE_KEY)}
    merged.update(topology_metadata(writers, readers, role))
    return merged
