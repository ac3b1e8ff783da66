"""What Rerun's web viewer shows, read from the viewer itself, and what a ``.rrd``'s layout names.

The web viewer draws on a canvas, so its panels are not in the page's DOM. Its page keeps the
viewer's handle as ``window._handle``; ``viewer_state()`` returns the Viewer Control API's
``GetStateResponse`` (protobuf, rerun 0.41): the recordings open, the selected one, and every
view of the active layout with its id and title. :func:`decode_viewer_state` reads the fields
used here with a small wire-format reader (no generated code: rerun-sdk ships no Python
bindings for that message). :func:`blueprint_views` reads the views the blueprint stored in a
``.rrd`` names. Comparing the two tells whether the browser shows rocas's designed layout or
Rerun's automatic one (``tests/viewer/test_blueprint.py``, ``docs/images/make_screenshots.py``).
"""

from __future__ import annotations

import os
from dataclasses import dataclass

#: GetStateResponse fields: the selected recording's store id, the recordings, the views
_SELECTED, _RECORDINGS, _VIEWS = 2, 3, 5
#: a view's id and title; a recording's store id
_VIEW_ID, _VIEW_TITLE, _RECORDING_ID = 1, 3, 1

#: JavaScript that returns the viewer's state as base64 (null before the viewer has started)
STATE_SCRIPT = ("const h = window._handle; if (!h) return null;"
                "const b = h.viewer_state(); let s = '';"
                "for (const x of b) s += String.fromCharCode(x); return btoa(s);")


@dataclass(frozen=True)
class ViewerState:
    """What the web viewer shows.

    Attributes:
        selected: the selected recording's store id (None: none).
        recordings: the store ids of the recordings open.
        views: view id -> title, for every view of the active layout.
    """

    selected: str | None
    recordings: tuple[str, ...]
    views: dict[str, str]


def _varint(b: bytes, i: int) -> tuple[int, int]:
    x = shift = 0
    while True:
        c = b[i]
        i += 1
        x |= (c & 0x7F) << shift
        shift += 7
        if c < 0x80:
            return x, i


def wire_fields(b: bytes) -> list[tuple[int, int | bytes]]:
    """A protobuf message's top-level fields as (number, value): an int for a varint, the bytes
    of a length-delimited field (a string or a sub-message) or of a fixed-width one.

    Raises:
        ValueError: a wire type protobuf no longer uses (groups), or bytes cut short.
    """
    out: list[tuple[int, int | bytes]] = []
    i = 0
    while i < len(b):
        key, i = _varint(b, i)
        number, wire = key >> 3, key & 7
        value: int | bytes
        if wire == 0:
            value, i = _varint(b, i)
        elif wire == 2:
            n, i = _varint(b, i)
            value, i = b[i:i + n], i + n
        elif wire in (1, 5):
            width = 8 if wire == 1 else 4
            value, i = b[i:i + width], i + width
        else:
            raise ValueError(f"protobuf wire type {wire} at byte {i}")
        if i > len(b):
            raise ValueError("protobuf message cut short")
        out.append((number, value))
    return out


def _strings(b: bytes, number: int) -> list[bytes]:
    return [v for n, v in wire_fields(b) if n == number and isinstance(v, bytes)]


def decode_viewer_state(data: bytes) -> ViewerState:
    """The :class:`ViewerState` of an encoded ``GetStateResponse``."""
    selected = _strings(data, _SELECTED)
    views = {}
    for v in _strings(data, _VIEWS):
        ids, titles = _strings(v, _VIEW_ID), _strings(v, _VIEW_TITLE)
        if ids:
            views[ids[0].decode()] = titles[0].decode() if titles else ""
    recordings = tuple(_strings(r, _RECORDING_ID)[0].decode()
                       for r in _strings(data, _RECORDINGS) if _strings(r, _RECORDING_ID))
    return ViewerState(selected[0].decode() if selected else None, recordings, views)


def viewer_state(driver: object) -> ViewerState | None:
    """The state of the web viewer in the (frame of the) page a selenium ``driver`` is on, or
    None before the viewer has started."""
    import base64

    data = driver.execute_script(STATE_SCRIPT)  # type: ignore[attr-defined]
    return None if data is None else decode_viewer_state(base64.b64decode(data))


def wait_for_views(driver: object, timeout_s: float = 180.0, poll_s: float = 3.0) -> ViewerState:
    """The viewer's state once a recording is open and its views have stopped changing
    between two polls (the last state seen when ``timeout_s`` runs out)."""
    import time

    deadline = time.monotonic() + timeout_s
    last = None
    while time.monotonic() < deadline:
        state = viewer_state(driver)
        if state is not None and state.recordings and state.views and state == last:
            return state
        last = state
        time.sleep(poll_s)
    return last or ViewerState(None, (), {})


def blueprint_views(rrd: str | os.PathLike[str]) -> dict[str, str]:
    """The views (id -> title) the blueprint stored in ``rrd`` names (empty without one)."""
    from rerun.chunk import RrdReader

    reader = RrdReader(rrd)
    views: dict[str, str] = {}
    for store in reader.blueprints():
        for chunk in reader.stream(store=store):
            batch = chunk.to_record_batch()
            column = next((f.name for f in batch.schema
                           if f.name.endswith("ViewBlueprint:display_name")), None)
            if column is not None:
                views[str(chunk.entity_path).rsplit("/", 1)[-1]] = batch.column(column).to_pylist()[-1][0]
    return views


def layout_problem(state: ViewerState, rrd: str | os.PathLike[str]) -> str | None:
    """Why ``state`` is not ``rrd``'s designed layout opened on its one recording, or None."""
    designed = blueprint_views(rrd)
    if not designed:
        return f"{rrd} names no layout"
    if state.views != designed:
        return (f"the viewer shows the views {sorted(state.views.values())}, the blueprint names "
                f"{sorted(designed.values())}")
    if len(state.recordings) != 1:
        return f"{len(state.recordings)} recordings are open: {list(state.recordings)}"
    if state.selected != state.recordings[0]:
        return f"the recording selected is {state.selected}, not {state.recordings[0]}"
    return None
