"""Opening a Rerun recording stream that writes a ``.rrd`` file atomically.

rocas writes the file itself: Rerun encodes into an in-memory stream (``rerun.binary_stream``)
and rocas writes its bytes with Python's file API. Rerun's own file sink reports a failed
write (a full disk) only as Rust log lines on stderr, and its flush then waits forever for the
writer thread that died; written here, a failed write is an ``OSError`` that rocas reports in
one line (a full disk: exit 5), and no Rust log reaches the terminal (:mod:`rocas.viz`).
"""

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
    """Yield a ``rerun.RecordingStream``; when the block ends without error, save it to ``path``.

    ``kind`` names what the file holds (``diff``, ``analysis``, ``view``) in the id;
    ``blueprint`` becomes the file's default layout and its active one: the native viewer
    shows a default layout, but Rerun's web viewer falls back to its automatic layout unless
    the blueprint is also made active (``tests/viewer/test_blueprint.py`` checks both views).
    The stream is kept in memory (the ``.rrd``'s size: a few MB for an analysis) and written
    under a temporary name that is renamed on success; nothing is written when the block
    raises.

    Raises:
        OutputError: the file cannot be written (a full disk, a folder not writable).
    """
    import rerun as rr

    rec = rr.RecordingStream(APPLICATION_ID, recording_id=new_recording_id(kind))
    stream = rr.binary_stream(recording=rec)
    if blueprint is not None:
        rec.send_blueprint(blueprint, make_active=True, make_default=True)
    try:
        yield rec
        data = stream.read(flush=True) or b""
    finally:
        rec.disconnect()
    with atomic_path(path) as tmp, open(tmp, "wb") as f:
        f.write(data)
