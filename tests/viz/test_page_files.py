"""The browser view's page (viewer/) is found by ``rocas view --web`` in a checkout and in an
installed wheel, and an sdist carries it (rocas.viz.campaign_web.viewer_dir)."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
import tarfile
import zipfile
from pathlib import Path

import pytest

from rocas.viz.campaign_web import viewer_dir

REPO = Path(__file__).resolve().parents[2]
PAGE_FILES = ("index.html", "app.js", "style.css")


def test_viewer_dir_serves_the_files_of_viewer():
    d = viewer_dir()
    for name in PAGE_FILES:
        assert (d / name).read_bytes() == (REPO / "viewer" / name).read_bytes()


def _source_copy(dst: Path) -> Path:
    """What a build reads (pyproject, README, the package, viewer/), links kept as links."""
    dst.mkdir()
    for name in ("pyproject.toml", "README.md"):
        shutil.copy2(REPO / name, dst / name)
    ignore = shutil.ignore_patterns("__pycache__", "*.egg-info")
    shutil.copytree(REPO / "rocas", dst / "rocas", symlinks=True, ignore=ignore)
    shutil.copytree(REPO / "viewer", dst / "viewer")
    return dst


def _build(src: Path, kind: str, out: Path) -> Path:
    code = (f"from setuptools import build_meta as b; print(b.build_{kind}({str(out)!r}))")
    r = subprocess.run([sys.executable, "-c", code], cwd=src, capture_output=True, text=True,
                       timeout=300)
    assert r.returncode == 0, r.stderr[-2000:]
    return out / r.stdout.strip().splitlines()[-1]


@pytest.mark.slow
def test_wheel_and_sdist_carry_the_page_and_an_installed_wheel_finds_it(tmp_path):
    pytest.importorskip("setuptools", reason="building the wheel needs setuptools")
    src = _source_copy(tmp_path / "src")
    dist = tmp_path / "dist"
    dist.mkdir()
    wheel = _build(src, "wheel", dist)
    with zipfile.ZipFile(wheel) as z:
        for name in PAGE_FILES:
            assert z.read(f"rocas/viz/page/{name}") == (REPO / "viewer" / name).read_bytes()
        site = tmp_path / "site"
        z.extractall(site)
    sdist = _build(src, "sdist", dist)
    with tarfile.open(sdist) as t:
        members = {m.name.partition("/")[2]: m for m in t.getmembers()}
        for name in PAGE_FILES:
            m = members[f"rocas/viz/page/{name}"]
            assert m.isfile()  # the file itself, not the checkout's link
            assert t.extractfile(m).read() == (REPO / "viewer" / name).read_bytes()
    # the installed wheel (no viewer/ beside it) serves the page from the package
    r = subprocess.run([sys.executable, "-c", "from rocas.viz.campaign_web import viewer_dir; "
                        "print(viewer_dir())"], cwd=tmp_path, capture_output=True, text=True,
                       env={**os.environ, "PYTHONPATH": str(site)}, timeout=120)
    assert r.returncode == 0, r.stderr[-2000:]
    assert Path(r.stdout.strip()) == site / "rocas" / "viz" / "page"
