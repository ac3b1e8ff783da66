"""A headless screenshot of the default layout (needs the rerun CLI and a Vulkan driver,
e.g. Debian's mesa-vulkan-drivers for the lavapipe software rasterizer)."""

import dataclasses
import glob
import os
import shutil
import subprocess

import numpy as np
import pytest

from rocas.scenarios.loader import load_example
from rocas.sim.engine import simulate
from rocas.viz.analysis import write_analysis_rrd
from rocas.viz.scene import BACKGROUND_RGB

ICD_DIRS = ("/usr/share/vulkan/icd.d", "/etc/vulkan/icd.d", "/usr/local/share/vulkan/icd.d")


def _skip_reason() -> str | None:
    if shutil.which("rerun") is None:
        return "the rerun CLI is not on PATH"
    if (
        not any(glob.glob(os.path.join(d, "*.json")) for d in ICD_DIRS)
        and "VK_ICD_FILENAMES" not in os.environ
    ):
        return "no Vulkan driver (apt-get install -y mesa-vulkan-drivers)"
    return None


@pytest.mark.skipif(_skip_reason() is not None, reason=_skip_reason() or "")
def test_headless_screenshot_of_the_default_layout_is_not_blank(tmp_path):
    Image = pytest.importorskip("PIL.Image")

    path = tmp_path / "accident.mcap"
    simulate(dataclasses.replace(load_example("roundabout_red_truck"), duration_s=8.0), output=path)
    rrd = tmp_path / "a.rrd"
    write_analysis_rrd(rrd, accident=path, verdict_md="# Verdict\n\nscreenshot test\n")
    png = tmp_path / "shot.png"
    runtime = tmp_path / "xdg"
    runtime.mkdir(mode=0o700)
    env = {**os.environ, "XDG_RUNTIME_DIR": str(runtime)}
    # the file goes through stdin: the viewer has it all before the first frame is drawn
    with open(rrd, "rb") as stdin:
        proc = subprocess.run(
            [
                "rerun",
                "--headless",
                "--window-size",
                "1280x720",
                "--screenshot-to",
                str(png),
                "--port",
                "9877",
                "-",
            ],
            stdin=stdin,
            capture_output=True,
            text=True,
            timeout=120,
            env=env,
        )
    if proc.returncode != 0 and ("No graphics adapter" in proc.stderr or "adapter" in proc.stderr.lower()):
        pytest.skip("the viewer found no graphics adapter")
    assert proc.returncode == 0, proc.stderr[-2000:]
    img = np.asarray(Image.open(png).convert("RGB")).astype(np.int16)
    assert img.shape[0] >= 700 and img.std() > 10
    assert len(np.unique(img.reshape(-1, 3), axis=0)) > 200
    # the scene view is drawn: a good share of pixels has its background colour
    scene = (np.abs(img - np.array(BACKGROUND_RGB)).sum(axis=2) < 12).mean()
    assert scene > 0.05
