"""Reading a .rrd back for assertions."""

from collections import defaultdict
from dataclasses import dataclass, field


@dataclass
class EntityInfo:
    rows: int = 0
    static_rows: int = 0
    timelines: set[str] = field(default_factory=set)
    columns: set[str] = field(default_factory=set)


def read_rrd(path) -> tuple[dict[str, EntityInfo], int]:
    """(entity path -> rows/timelines/components, number of blueprints)."""
    from rerun.chunk import RrdReader

    reader = RrdReader(path)
    (store,) = reader.recordings()
    entities: dict[str, EntityInfo] = defaultdict(EntityInfo)
    for chunk in reader.stream(store=store):
        info = entities[str(chunk.entity_path)]
        if chunk.is_static:
            info.static_rows += chunk.num_rows
        else:
            info.rows += chunk.num_rows
        info.timelines.update(chunk.timeline_names)
        info.columns.update(f.name for f in chunk.to_record_batch().schema)
    return dict(entities), len(reader.blueprints())
