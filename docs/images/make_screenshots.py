"""Regenerate the README's and docs/viewer.md's pictures from the current code, each with the
facts it shows written beside it (``NAME.json``), which the test suite compares with the code.

- ``rerun-view.png``: the README's quick start (``rocas analyze
  recordings/a09_red_truck_roundabout.mcap``) in the native Rerun viewer, headless at 1600x900
  with the time cursor on the accident (needs a Vulkan driver: ``apt-get install -y
  mesa-vulkan-drivers``).
- ``triage-view.png``: ``rocas triage`` of the shipped recordings in :data:`CAMPAIGN` and its
  browser page (``rocas view --web``) in headless chromium at 1600x900, with the quick start's
  accident opened in Rerun's web viewer; the picture is taken only once the viewer shows
  rocas's designed layout on that one recording (needs selenium, Debian's ``chromium`` and
  ``chromium-driver``).

Each ``NAME.json`` holds the command that made the picture, the facts it shows (trigger,
module, misconfiguration; the campaign's groups) and the picture's SHA-256: a picture replaced
by hand, or facts the code no longer gives, fail ``tests/viz/test_readme_pictures.py``::

    python docs/images/make_screenshots.py [--run-dir RUN_DIR] [--only rerun-view|triage-view]

``--run-dir`` reuses a finished run directory of the quick start instead of analysing again.
"""

from __future__ import annotations

import argparse
import hashlib
import json
import os
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[2]
IMAGES = ROOT / "docs" / "images"
RECORDING = ROOT / "recordings" / "a09_red_truck_roundabout.mcap"
#: the campaign of the triage picture: shipped recordings, the quick start's first
CAMPAIGN = ("a09_red_truck_roundabout", "a10_skewed_junction_light", "a07_rear_ended_at_red")
SIZE = (1600, 900)


def report_facts(report: dict[str, Any]) -> dict[str, Any]:
    """What the analysis picture shows of a report, as the terminal words it."""
    from rocas.pipeline.report import change

    trig = report.get("triggering_entity") or {}
    return {
        "verdict": report["verdict"],
        "triggering_entity": (f"{trig['entity']} ({trig['kind']}): "
                              + ", ".join(change(p, "->") for p in trig["properties"])) if trig else None,
        "deviating_module": report.get("deviating_module"),
        "misconfiguration": [change(m, "->") for m in report["misconfiguration"]],
    }


def campaign_facts(campaign: dict[str, Any]) -> dict[str, Any]:
    """What the triage picture shows of a campaign: its accidents, groups and failures."""
    return {
        "accidents": sorted(a["name"] for a in campaign["accidents"]),
        "groups": [{"root_cause": g["root_cause"], "count": g["count"],
                    "documented": g.get("documented")} for g in campaign["groups"]],
        "failed": [f["name"] for f in campaign["failed"]],
    }


def sha256(path: Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


def _sidecar(png: Path, command: str, facts: dict[str, Any]) -> None:
    doc = {"made_by": "python docs/images/make_screenshots.py", "command": command,
           "facts": facts, "png_sha256": sha256(png)}
    png.with_suffix(".json").write_text(json.dumps(doc, indent=2) + "\n", encoding="utf-8")


def _rocas(*argv: str) -> None:
    subprocess.run([sys.executable, "-m", "rocas", *argv], check=True, cwd=ROOT)


def rerun_view(run_dir: Path | None, tmp: Path) -> None:
    from rocas.viz.analysis import write_run_dir_rrd
    from rocas.viz.screenshot import screenshot_rrd

    if run_dir is None:
        run_dir = tmp / "run"
        _rocas("analyze", str(RECORDING), "--out", str(run_dir), "--quiet")
    rrd = tmp / "view.rrd"
    contents = write_run_dir_rrd(rrd, run_dir)
    acc = contents["accident"].accident()
    png = IMAGES / "rerun-view.png"
    shot = screenshot_rrd(rrd, png, size=SIZE, time_s=None if acc is None else acc[0])[0]
    problems = {v: p for v, p in shot.views.items() if p}
    if problems:
        raise SystemExit(f"views with problems: {problems}")
    _sidecar(png, f"rocas analyze recordings/{RECORDING.name}", report_facts(contents["report"]))
    print(f"wrote {png}")


def _browser(tmp: Path) -> Any:
    from selenium import webdriver

    opts = webdriver.ChromeOptions()
    opts.binary_location = shutil.which("chromium") or shutil.which("chromium-browser") or "chromium"
    for flag in ("--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
                 "--disable-background-networking", "--disable-component-update", "--disable-sync",
                 "--enable-unsafe-swiftshader", f"--window-size={SIZE[0]},{SIZE[1]}",
                 "--hide-scrollbars", f"--user-data-dir={tmp / 'chromium'}"):
        opts.add_argument(flag)
    service = webdriver.ChromeService(executable_path=shutil.which("chromedriver") or "chromedriver")
    return webdriver.Chrome(options=opts, service=service)


def triage_view(tmp: Path) -> None:
    from selenium.webdriver.common.by import By
    from selenium.webdriver.support import expected_conditions as ec
    from selenium.webdriver.support.ui import WebDriverWait

    from rocas.viz.campaign_web import CampaignServer
    from rocas.viz.serve import free_port
    from rocas.viz.web_state import layout_problem, wait_for_views

    out = tmp / "campaign"
    _rocas("triage", *(str(ROOT / "recordings" / f"{n}.mcap") for n in CAMPAIGN), "--out", str(out),
           "--quiet")
    campaign = json.loads((out / "campaign.json").read_text(encoding="utf-8"))
    server = CampaignServer(out, port=0, web_viewer_port=free_port())
    server.start()
    driver = _browser(tmp)
    try:
        driver.get(server.url)
        WebDriverWait(driver, 60).until(lambda d: d.find_elements(By.CSS_SELECTOR, "tr.accident-row"))
        driver.find_element(By.CSS_SELECTOR, f'tr.accident-row[data-name="{CAMPAIGN[0]}"]').click()
        WebDriverWait(driver, 60).until(ec.frame_to_be_available_and_switch_to_it((By.ID, "rerun")))
        state = wait_for_views(driver)
        driver.switch_to.default_content()
        problem = layout_problem(state, out / "rrd" / f"{CAMPAIGN[0]}.rrd")
        if problem:
            raise SystemExit(f"the browser does not show the designed layout: {problem}")
        time.sleep(5)  # the viewer finishes drawing what it has loaded
        png = IMAGES / "triage-view.png"
        driver.save_screenshot(str(png))
    finally:
        driver.quit()
        server.stop()
    names = " ".join(f"recordings/{n}.mcap" for n in CAMPAIGN)
    _sidecar(png, f"rocas triage {names}; rocas view --web runs/campaign", campaign_facts(campaign))
    print(f"wrote {png}")


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--run-dir", type=Path, help="a finished run directory of the quick start")
    p.add_argument("--only", choices=("rerun-view", "triage-view"), help="make one picture")
    args = p.parse_args(argv)
    os.environ.setdefault("PYTHONPATH", str(ROOT))
    with tempfile.TemporaryDirectory(prefix="rocas-shots-") as name:
        tmp = Path(name)
        if args.only in (None, "rerun-view"):
            rerun_view(args.run_dir, tmp)
        if args.only in (None, "triage-view"):
            triage_view(tmp)
    return 0


if __name__ == "__main__":
    sys.exit(main())
