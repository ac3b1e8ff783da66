"""Opening a Rerun recording stream that writes a ``.rrd`` file atomically."""

from __future__ import annotations

import contextlib
import os
import uuid
from collections.abc import Iterator
from typing import Any

from rocas._fs import atomic_path

APPLICATION_ID = "rocas"


def new_recording_id(kind: str) -> str:
    """A recording id of its own for every ``.rrd`` (``rocas-<kind>-<random uuid>``).

    The viewer merges everything sent under one recording id, so two files that shared one
    (two diffs opened together) would show as one recording.
    """
    return f"rocas-{kind}-{uuid.uuid4()}"


@contextlib.contextmanager
def rrd_recording(
    path: str | os.PathLike[str], blueprint: Any | None = None, kind: str = "recording"
) -> Iterator[Any]:
    """Yield a ``rerun.RecordingStream`` saving to ``path``, under a fresh recording id.

    ``kind`` names what the file holds (``diff``, ``analysis``, ``view``) in the id. The file is
    written under a temporary name and renamed on success, after the stream is disconnected
    (which writes the ``.rrd`` footer).
    """
    import rerun as rr

    with atomic_path(path) as tmp:
        rec = rr.RecordingStream(APPLICATION_ID, recording_id=new_recording_id(kind))
        rec.save(tmp, default_blueprint=blueprint)
        try:
            yield rec
        finally:
            rec.flush()
            rec.disconnect()
