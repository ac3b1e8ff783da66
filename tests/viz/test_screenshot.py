"""Headless screenshots of the default layouts at 1600x900 (need the rerun viewer and a Vulkan
driver, e.g. Debian's mesa-vulkan-drivers for the lavapipe software rasterizer)."""

import dataclasses

import numpy as np
import pytest
from foreign_stack import make_pair

from rocas.analysis import diff
from rocas.rollout import simulate
from rocas.scenarios.loader import load_example
from rocas.viz.analysis import write_analysis_rrd
from rocas.viz.diff import ORANGE, RED, write_diff_rrd
from rocas.viz.draw import BACKGROUND_RGB
from rocas.viz.screenshot import screenshot_rrd, unavailable_reason

pytestmark = [pytest.mark.slow,
              pytest.mark.skipif(unavailable_reason() is not None, reason=unavailable_reason() or "")]


def _image(path):
    Image = pytest.importorskip("PIL.Image")
    return np.asarray(Image.open(path).convert("RGB")).astype(np.int16)


def _share(img, rgb, tol=40):
    return (np.abs(img - np.array(rgb)).sum(axis=2) < tol).mean()


@pytest.mark.slow  # a Rerun viewer, about 10 s
def test_analysis_layout_at_1600x900(tmp_path):
    path = tmp_path / "accident.mcap"
    simulate(dataclasses.replace(load_example("roundabout_red_truck"), duration_s=8.0), output=path)
    rrd = tmp_path / "a.rrd"
    write_analysis_rrd(rrd, accident=path, verdict_md="# Verdict\n\nscreenshot test\n")
    shot, = screenshot_rrd(rrd, tmp_path / "shot.png", time_s=6.0)
    assert not any(shot.views.values()), shot.views  # every view drew without a problem
    img = _image(shot.png)
    assert img.shape[:2] == (900, 1600) and img.std() > 10
    assert _share(img, BACKGROUND_RGB, 12) > 0.05  # the scene view is drawn


@pytest.mark.slow  # a Rerun viewer, about 10 s
def test_third_party_diff_shows_the_walk_in_the_cmg_view(tmp_path):
    pair = make_pair(tmp_path, deviating="forecaster")
    result = diff(pair.accident, pair.reference)
    assert result.deviating_module == "forecaster"
    rrd = tmp_path / "d.rrd"
    write_diff_rrd(result, rrd)
    whole, cmg = screenshot_rrd(rrd, tmp_path / "diff.png", views=["CMG after Algorithm 1"])
    assert not any(whole.views.values()), whole.views
    img = _image(cmg.png)
    # the walk's dots and labels in orange, the deviating module in red: both on screen
    assert _share(img, ORANGE) > 0.0005 and _share(img, RED) > 0.00003


def test_a_stopped_viewer_leaves_no_process_behind():
    psutil = pytest.importorskip("psutil")
    from rocas.viz.screenshot import headless_viewer

    with headless_viewer() as viewer:
        # the environment's `rerun` script and the viewer binary it starts
        family = [psutil.Process(viewer.proc.pid), *psutil.Process(viewer.proc.pid).children(recursive=True)]
    gone, alive = psutil.wait_procs(family, timeout=5)
    assert not alive, [p.cmdline()[:2] for p in alive]
