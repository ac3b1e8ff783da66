"""Opening a Rerun recording stream that writes a ``.rrd`` file atomically."""

from __future__ import annotations

import contextlib
import os
from collections.abc import Iterator
from typing import Any

from rocas._fs import atomic_path

APPLICATION_ID = "rocas"


@contextlib.contextmanager
def rrd_recording(
    path: str | os.PathLike[str], blueprint: Any | None = None, recording_id: str = "rocas"
) -> Iterator[Any]:
    """Yield a ``rerun.RecordingStream`` saving to ``path``.

    The file is written under a temporary name and renamed on success, after the stream is
    disconnected (which writes the ``.rrd`` footer).
    """
    import rerun as rr

    with atomic_path(path) as tmp:
        rec = rr.RecordingStream(APPLICATION_ID, recording_id=recording_id)
        rec.save(tmp, default_blueprint=blueprint)
        try:
            yield rec
        finally:
            rec.flush()
            rec.disconnect()
