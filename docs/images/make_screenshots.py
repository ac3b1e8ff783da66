"""Regenerate the README's picture (docs/images/rerun-view.png) from the current code.

Runs the README's quick start (``rocas analyze recordings/a09_red_truck_roundabout.mcap``) into
a temporary run directory, writes its ``.rrd`` with the default layout, and screenshots it in a
headless Rerun viewer at 1600x900 with the time cursor on the accident. Needs a Vulkan driver
(``apt-get install -y mesa-vulkan-drivers``)::

    python docs/images/make_screenshots.py [--run-dir RUN_DIR] [--out PNG]

``--run-dir`` reuses a finished run directory instead of analysing again.
"""

from __future__ import annotations

import argparse
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
RECORDING = ROOT / "recordings" / "a09_red_truck_roundabout.mcap"


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--run-dir", type=Path, help="a finished 'rocas analyze' run directory")
    p.add_argument("--out", type=Path, default=ROOT / "docs" / "images" / "rerun-view.png")
    args = p.parse_args(argv)

    from rocas.viz.analysis import write_run_dir_rrd
    from rocas.viz.screenshot import screenshot_rrd

    with tempfile.TemporaryDirectory(prefix="rocas-shots-") as tmp:
        run_dir = args.run_dir
        if run_dir is None:
            run_dir = Path(tmp) / "run"
            subprocess.run([sys.executable, "-m", "rocas.cli.main", "analyze", str(RECORDING),
                            "--out", str(run_dir)], check=True)
        rrd = Path(tmp) / "view.rrd"
        contents = write_run_dir_rrd(rrd, run_dir)
        acc = contents["accident"].accident()
        shot = screenshot_rrd(rrd, args.out, time_s=None if acc is None else acc[0])[0]
    problems = {v: p for v, p in shot.views.items() if p}
    print(f"wrote {shot.png}" + (f"; views with problems: {problems}" if problems else ""))
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
