"""The browser view shows rocas's designed layout, not Rerun's automatic one (issue 40).

Rerun's web viewer draws on a canvas; what it shows is read from the viewer itself: its page
keeps the viewer's handle as ``window._handle``, whose ``viewer_state()`` is the Viewer Control
API's ``GetStateResponse`` (protobuf): the recordings open, the selected one, and every view
of the active layout with its id and title. The test compares those views with the ones the
blueprint in the served ``.rrd`` names, id for id and title for title: when the viewer falls
back to its automatic layout, the views are its own (titled by entity path) and the test fails.
It checks both ways into the browser: ``rocas view RUN_DIR`` without a display (the web viewer
fed through Rerun's gRPC proxy) and the campaign page (the ``.rrd`` fetched over HTTP).
"""

import base64
import socket
import time
from pathlib import Path

import pytest

pytestmark = pytest.mark.slow

#: GetStateResponse fields (rerun 0.41, viewer_control.v1alpha1): the selected recording's
#: store id, the recordings, the views of the active blueprint
_SELECTED, _RECORDINGS, _VIEWS = 2, 3, 5
#: a view's id and title, a recording's store id
_VIEW_ID, _VIEW_TITLE, _RECORDING_ID = 1, 3, 1


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def _varint(b: bytes, i: int) -> tuple[int, int]:
    x = shift = 0
    while True:
        c = b[i]
        i += 1
        x |= (c & 0x7F) << shift
        shift += 7
        if c < 0x80:
            return x, i


def _fields(b: bytes) -> list[tuple[int, object]]:
    """A protobuf message's top-level fields as (number, value): ints for varints, bytes for
    length-delimited fields (strings and sub-messages), raw bytes for fixed-width ones."""
    out, i = [], 0
    while i < len(b):
        key, i = _varint(b, i)
        number, wire = key >> 3, key & 7
        if wire == 0:
            value, i = _varint(b, i)
        elif wire == 2:
            n, i = _varint(b, i)
            value, i = b[i:i + n], i + n
        elif wire in (1, 5):
            width = 8 if wire == 1 else 4
            value, i = b[i:i + width], i + width
        else:
            raise ValueError(f"wire type {wire}")
        out.append((number, value))
    return out


def _field(b: bytes, number: int) -> list:
    return [v for n, v in _fields(b) if n == number]


def viewer_state(driver) -> dict:
    """The selected recording, the recordings and the views (id -> title) the viewer shows."""
    data = driver.execute_script(
        "const h = window._handle; if (!h) return null;"
        "const b = h.viewer_state(); let s = ''; for (const x of b) s += String.fromCharCode(x);"
        "return btoa(s);")
    if data is None:
        return {"selected": None, "recordings": [], "views": {}}
    state = base64.b64decode(data)
    selected = _field(state, _SELECTED)
    return {
        "selected": selected[0].decode() if selected else None,
        "recordings": [_field(r, _RECORDING_ID)[0].decode() for r in _field(state, _RECORDINGS)],
        "views": {_field(v, _VIEW_ID)[0].decode(): _field(v, _VIEW_TITLE)[0].decode()
                  for v in _field(state, _VIEWS)},
    }


def blueprint_views(rrd: Path) -> dict[str, str]:
    """The views (id -> title) the blueprint stored in ``rrd`` names."""
    from rerun.chunk import RrdReader

    reader = RrdReader(rrd)
    (store,) = reader.blueprints()
    views = {}
    for chunk in reader.stream(store=store):
        batch = chunk.to_record_batch()
        column = next((f.name for f in batch.schema if f.name.endswith("ViewBlueprint:display_name")),
                      None)
        if column is not None:
            view_id = str(chunk.entity_path).rsplit("/", 1)[-1]
            views[view_id] = batch.column(column).to_pylist()[-1][0]
    return views


def _wait_for_views(driver, timeout_s: float = 180.0) -> dict:
    """The viewer's state once its recording is loaded and its views have stopped changing."""
    deadline = time.monotonic() + timeout_s
    last = None
    while time.monotonic() < deadline:
        state = viewer_state(driver)
        if state["recordings"] and state["views"] and state == last:
            return state
        last = state
        time.sleep(3.0)
    return last or {"selected": None, "recordings": [], "views": {}}


def check_designed_layout(state: dict, rrd: Path) -> None:
    designed = blueprint_views(rrd)
    assert len(designed) >= 10  # the analysis layout: scenes, signals, CMG, MDR, searches, verdict
    shown = state["views"]
    # every panel title the blueprint names, under its own view id, and no view of Rerun's own
    assert shown == designed, (f"the viewer shows {sorted(shown.values())}, the blueprint names "
                               f"{sorted(designed.values())}")
    # one recording, the analysis, selected
    assert len(state["recordings"]) == 1, state["recordings"]
    assert "rocas-analysis-" in state["recordings"][0]
    assert state["selected"] == state["recordings"][0]


def test_view_without_a_display_serves_the_designed_layout(browser, small_campaign, tmp_path):
    from urllib.parse import quote

    from rocas.cli.view import write_rrd
    from rocas.viz.serve import RerunWebServer

    out, _ = small_campaign
    rrd = tmp_path / "view.rrd"
    write_rrd(out / "runs" / "red_truck", rrd)  # what 'rocas view RUN_DIR' serves
    server = RerunWebServer("127.0.0.1", _free_port(), _free_port(), sources=[str(rrd)])
    server.start()
    try:
        browser.get(f"http://127.0.0.1:{server.web_port}/?url={quote(server.grpc_url, safe=':/')}")
        check_designed_layout(_wait_for_views(browser), rrd)
    finally:
        server.stop()


def test_the_campaign_page_opens_an_accident_in_the_designed_layout(browser, small_campaign):
    from selenium.webdriver.common.by import By
    from selenium.webdriver.support import expected_conditions as ec
    from selenium.webdriver.support.ui import WebDriverWait

    from rocas.viz.campaign_web import CampaignServer

    out, campaign = small_campaign
    server = CampaignServer(out, port=0, web_viewer_port=_free_port())
    server.start()
    try:
        browser.get(server.url)
        WebDriverWait(browser, 60).until(lambda d: d.find_elements(By.CSS_SELECTOR, "tr.accident-row"))
        name = campaign["accidents"][0]["name"]
        browser.find_element(By.CSS_SELECTOR, f'tr.accident-row[data-name="{name}"]').click()
        WebDriverWait(browser, 60).until(ec.frame_to_be_available_and_switch_to_it((By.ID, "rerun")))
        state = _wait_for_views(browser)
        browser.switch_to.default_content()
        check_designed_layout(state, out / "rrd" / f"{name}.rrd")
    finally:
        server.stop()


def test_the_state_decoder_reads_what_it_is_given():
    view = bytes([0x0A, 2]) + b"v1" + bytes([0x12, 2]) + b"2D" + bytes([0x1A, 5]) + b"Scene"
    rec = bytes([0x0A, 3]) + b"r-1"
    state = bytes([0x12, 3]) + b"r-1" + bytes([0x1A, len(rec)]) + rec + bytes([0x2A, len(view)]) + view
    assert _field(state, _SELECTED) == [b"r-1"]
    assert [_field(v, _VIEW_TITLE) for v in _field(state, _VIEWS)] == [[b"Scene"]]
