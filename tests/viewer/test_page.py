"""The campaign page in a real headless browser (Debian's chromium and chromedriver): it
loads with no console error, its groups table is campaign.json's, and Rerun's web viewer
shows its canvas for a selected accident."""

import socket

import pytest

pytestmark = pytest.mark.slow


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


@pytest.fixture(scope="module")
def server(small_campaign):
    from rocas.viz.campaign_web import CampaignServer

    out, _ = small_campaign
    srv = CampaignServer(out, port=0, web_viewer_port=_free_port())
    srv.start()
    yield srv
    srv.stop()


def _screenshot(driver):
    """Where ROCAS_SCREENSHOT names a file, keep a picture of the page there."""
    import os

    if os.environ.get("ROCAS_SCREENSHOT"):
        import time

        time.sleep(10)  # the viewer draws the recording
        driver.save_screenshot(os.environ["ROCAS_SCREENSHOT"])


def _outside(e) -> bool:
    """Rerun's web viewer calls its makers' hosts (usage analytics, a check for a newer release);
    with no network here those requests fail to resolve. They are the only errors let through:
    any error of the page, of a script or of a request to this machine fails the test."""
    msg = e["message"]
    unresolved = (e.get("source") == "network" and "net::ERR_NAME_NOT_RESOLVED" in msg
                  and not msg.startswith("http://127.0.0.1"))
    # the viewer's own report of such a call ("Failed to fetch" thrown inside re_viewer.js)
    viewer_fetch = e.get("source") == "console-api" and "/rerun/re_viewer.js" in msg \
        and "TypeError: Failed to fetch" in msg
    return unresolved or viewer_fetch


def _errors(driver):
    return [e for e in driver.get_log("browser") if e["level"] == "SEVERE" and not _outside(e)]


@pytest.mark.slow  # a browser and a campaign, about 12 s
def test_the_page_shows_the_groups_and_opens_an_accident_in_rerun(browser, server, small_campaign):
    from selenium.webdriver.common.by import By
    from selenium.webdriver.support import expected_conditions as ec
    from selenium.webdriver.support.ui import WebDriverWait

    _, campaign = small_campaign
    browser.get(server.url)
    wait = WebDriverWait(browser, 60)
    wait.until(lambda d: d.find_elements(By.CSS_SELECTOR, "#groups tbody tr"))
    rows = [[td.text for td in tr.find_elements(By.TAG_NAME, "td")]
            for tr in browser.find_elements(By.CSS_SELECTOR, "#groups tbody tr")]
    assert [r[:3] for r in rows] == [[g["id"], g["root_cause"], str(g["count"])] for g in campaign["groups"]]
    # the terminal's "documented root cause" column, and what "agreement" means
    headers = [th.text for th in browser.find_elements(By.CSS_SELECTOR, "#groups thead th")]
    assert headers[-1] == "documented root cause" and len(headers) == len(rows[0])
    assert [r[-1] for r in rows] == [{True: "yes", False: "no"}.get(g.get("documented"), "")
                                     for g in campaign["groups"]]
    legend = browser.find_element(By.ID, "legend").text
    for word in ("agreement", "stable", "contested", "unstable", "documented root cause"):
        assert word in legend
    assert "failed: broken" in browser.find_element(By.ID, "failed").text
    assert _errors(browser) == []

    name = campaign["accidents"][0]["name"]
    browser.find_element(By.CSS_SELECTOR, f'tr.accident-row[data-name="{name}"]').click()
    wait.until(ec.frame_to_be_available_and_switch_to_it((By.ID, "rerun")))
    canvas = WebDriverWait(browser, 240).until(
        lambda d: next((c for c in d.find_elements(By.ID, "the_canvas_id")
                        if "visible" in c.get_attribute("class")), None))
    assert canvas.size["width"] > 100 and canvas.size["height"] > 100
    browser.switch_to.default_content()
    rrd = server.campaign_dir / "rrd" / f"{name}.rrd"
    WebDriverWait(browser, 120).until(lambda _: rrd.exists())  # the viewer asked for the analysis
    assert rrd.stat().st_size > 0
    _screenshot(browser)
    assert _errors(browser) == []
