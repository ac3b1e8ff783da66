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

import socket
from pathlib import Path

import pytest

pytestmark = pytest.mark.slow


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def check_designed_layout(state, rrd: Path) -> None:
    from rocas.viz.web_state import blueprint_views, layout_problem

    # the analysis layout: scenes, signals, CMG, MDR, searches, verdict
    assert len(blueprint_views(rrd)) >= 10
    assert layout_problem(state, rrd) is None, layout_problem(state, rrd)
    assert "rocas-analysis-" in state.recordings[0]


def test_view_without_a_display_serves_the_designed_layout(browser, small_campaign, tmp_path):
    from urllib.parse import quote

    from rocas.cli.view import write_rrd
    from rocas.viz.serve import RerunWebServer
    from rocas.viz.web_state import wait_for_views

    out, _ = small_campaign
    rrd = tmp_path / "view.rrd"
    write_rrd(out / "runs" / "red_truck", rrd)  # what 'rocas view RUN_DIR' serves
    server = RerunWebServer("127.0.0.1", _free_port(), _free_port(), sources=[str(rrd)])
    server.start()
    try:
        browser.get(f"http://127.0.0.1:{server.web_port}/?url={quote(server.grpc_url, safe=':/')}")
        check_designed_layout(wait_for_views(browser), rrd)
    finally:
        server.stop()


def test_the_campaign_page_opens_an_accident_in_the_designed_layout(browser, small_campaign):
    from selenium.webdriver.common.by import By
    from selenium.webdriver.support import expected_conditions as ec
    from selenium.webdriver.support.ui import WebDriverWait

    from rocas.viz.campaign_web import CampaignServer
    from rocas.viz.web_state import wait_for_views

    out, campaign = small_campaign
    server = CampaignServer(out, port=0, web_viewer_port=_free_port())
    server.start()
    try:
        browser.get(server.url)
        WebDriverWait(browser, 60).until(lambda d: d.find_elements(By.CSS_SELECTOR, "tr.accident-row"))
        name = campaign["accidents"][0]["name"]
        browser.find_element(By.CSS_SELECTOR, f'tr.accident-row[data-name="{name}"]').click()
        WebDriverWait(browser, 60).until(ec.frame_to_be_available_and_switch_to_it((By.ID, "rerun")))
        state = wait_for_views(browser)
        browser.switch_to.default_content()
        check_designed_layout(state, out / "rrd" / f"{name}.rrd")
    finally:
        server.stop()
