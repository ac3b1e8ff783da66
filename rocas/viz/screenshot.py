"""Headless screenshots of a ``.rrd`` in its default layout, as a person sees it in the viewer.

A ``rerun --headless`` viewer (no window; it needs a Vulkan driver, e.g. Mesa's lavapipe
software rasterizer) is started on a free local port, opens the file, waits until it is loaded,
moves the time cursor, and paints a screenshot of the whole window or of single views.
``docs/images/make_screenshots.py`` and the screenshot tests use it.
"""

from __future__ import annotations

import contextlib
import os
import shutil
import signal
import socket
import subprocess
import sys
import tempfile
import time
from collections.abc import Iterator, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from rocas.errors import RocasError

#: The window size of the README picture and the screenshot tests, in logical points.
DEFAULT_SIZE = (1600, 900)
#: Where Vulkan drivers register themselves (a headless viewer cannot start without one).
ICD_DIRS = ("/usr/share/vulkan/icd.d", "/etc/vulkan/icd.d", "/usr/local/share/vulkan/icd.d")


@dataclass(frozen=True)
class Shot:
    """What one screenshot showed.

    Attributes:
        png: the file written.
        views: view name -> problems the viewer reported for it (empty when it drew cleanly).
    """

    png: Path
    views: dict[str, list[str]]


def rerun_executable() -> str | None:
    """The ``rerun`` viewer of this Python environment (else the one on PATH), or None."""
    beside = Path(sys.executable).with_name("rerun")
    if beside.is_file() and os.access(beside, os.X_OK):
        return str(beside)
    return shutil.which("rerun")


def unavailable_reason() -> str | None:
    """Why a headless viewer cannot start here (no ``rerun``, no Vulkan driver), or None."""
    if rerun_executable() is None:
        return "the rerun viewer executable is not installed (pip install rerun-sdk)"
    has_icd = any(Path(d).is_dir() and any(Path(d).glob("*.json")) for d in ICD_DIRS)
    if not has_icd and "VK_ICD_FILENAMES" not in os.environ and "VK_DRIVER_FILES" not in os.environ:
        return "no Vulkan driver (apt-get install -y mesa-vulkan-drivers)"
    return None


#: How long the viewer's start-up notifications (software rasterizer, port) stay up [s].
NOTIFICATIONS_S = 7.0


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


class HeadlessViewer:
    """A running ``rerun --headless`` viewer and a client driving it (use :func:`headless_viewer`)."""

    def __init__(self, proc: subprocess.Popen[bytes], client: Any) -> None:
        self.proc = proc
        self.client = client
        self.started = time.monotonic()

    def open(self, rrd: str | os.PathLike[str], timeout_s: float = 60.0) -> None:
        """Open ``rrd`` (replacing what was open) and wait until it has loaded."""
        with contextlib.suppress(Exception):
            self.client.close("all")
        self.client.open(str(Path(rrd).resolve()))
        deadline = time.monotonic() + timeout_s
        while True:
            state = self.client.get_state()
            if not state.loading and state.recordings:
                return
            if time.monotonic() > deadline:
                raise RocasError(f"{rrd}: the headless viewer did not finish loading in {timeout_s:g} s")
            time.sleep(0.2)

    def views(self) -> dict[str, Any]:
        """View name -> the viewer's description of it (id, class, problems)."""
        return {v.name: v for v in self.client.get_state().views}

    def screenshot(
        self,
        png: str | os.PathLike[str],
        *,
        time_s: float | None = None,
        timeline: str = "sim_time",
        view: str | None = None,
        settle_s: float = 1.5,
    ) -> Shot:
        """Paint the whole window (or the view named ``view``) into ``png``.

        ``time_s``: where the time cursor goes on ``timeline`` first (default: where the viewer
        put it). ``settle_s``: how long the viewer runs before the picture is taken, so that
        graph layouts and notifications settle [s].
        """
        if time_s is not None:
            self.client.set_time(timeline, duration=float(time_s), play_state="paused")
        # the viewer's start-up notifications fade after a few seconds
        time.sleep(max(settle_s, NOTIFICATIONS_S - (time.monotonic() - self.started)))
        views = self.views()
        view_id = None
        if view is not None:
            if view not in views:
                raise RocasError(f"no view named {view!r} (views: {', '.join(sorted(views))})")
            view_id = views[view].view_id
        data = self.client.take_screenshot(view_id)
        out = Path(png)
        out.parent.mkdir(parents=True, exist_ok=True)
        out.write_bytes(data)
        problems = {n: [f"{r.severity}: {r.summary}" for r in v.reports] for n, v in self.views().items()}
        return Shot(out, problems)


@contextlib.contextmanager
def headless_viewer(size: Sequence[int] = DEFAULT_SIZE, start_timeout_s: float = 60.0
                    ) -> Iterator[HeadlessViewer]:
    """Start a headless viewer of ``size`` (width, height) logical points; stop it on exit.

    Raises:
        RocasError: no viewer executable or Vulkan driver, or the viewer did not start.
    """
    reason = unavailable_reason()
    if reason is not None:
        raise RocasError(f"cannot take a screenshot: {reason}")
    from rerun.experimental import ViewerClient

    port = _free_port()
    runtime = tempfile.mkdtemp(prefix="rocas-xdg-")
    os.chmod(runtime, 0o700)
    env = {**os.environ, "XDG_RUNTIME_DIR": runtime}
    cmd = [rerun_executable() or "rerun", "--headless", "--window-size", f"{size[0]}x{size[1]}",
           "--port", str(port), "--hide-welcome-screen"]
    log = tempfile.TemporaryFile()
    # a session of its own: the ``rerun`` of a virtual environment is a Python script that
    # starts the viewer binary as its child, and stopping the script alone leaves the viewer
    # running (each screenshot test left one behind, 300 MB and a share of a core each)
    proc = subprocess.Popen(cmd, env=env, stdout=subprocess.DEVNULL, stderr=log,
                            start_new_session=True)
    try:
        deadline = time.monotonic() + start_timeout_s
        while True:
            if proc.poll() is not None:
                log.seek(0)
                last = (log.read().decode(errors="replace").strip().splitlines() or ["no message"])[-1]
                raise RocasError(f"the headless Rerun viewer exited with status {proc.returncode}: {last}")
            try:
                client = ViewerClient.connect(f"rerun+http://127.0.0.1:{port}/proxy")
                client.get_state()
                break
            except Exception:
                if time.monotonic() > deadline:
                    raise RocasError(
                        f"the headless Rerun viewer did not answer within {start_timeout_s:g} s"
                    ) from None
                time.sleep(0.2)
        yield HeadlessViewer(proc, client)
    finally:
        _stop_group(proc)
        log.close()
        shutil.rmtree(runtime, ignore_errors=True)


def _stop_group(proc: subprocess.Popen[bytes]) -> None:
    """Stop ``proc`` and every process of its session (SIGTERM, then SIGKILL after 10 s)."""
    def signal_group(sig: int) -> None:
        try:
            os.killpg(proc.pid, sig)
        except ProcessLookupError:
            pass

    signal_group(signal.SIGTERM)
    try:
        proc.wait(timeout=10)
    except subprocess.TimeoutExpired:
        signal_group(signal.SIGKILL)
        proc.wait()
    # the viewer may outlive the script that started it by a moment
    deadline = time.monotonic() + 10
    while time.monotonic() < deadline:
        try:
            os.killpg(proc.pid, 0)
        except ProcessLookupError:
            return
        time.sleep(0.1)
    signal_group(signal.SIGKILL)


def screenshot_rrd(
    rrd: str | os.PathLike[str],
    png: str | os.PathLike[str],
    *,
    size: Sequence[int] = DEFAULT_SIZE,
    time_s: float | None = None,
    views: Sequence[str] = (),
) -> list[Shot]:
    """Screenshot ``rrd`` in its default layout into ``png`` (and each of ``views`` alone into
    ``<png stem>-<view>.png`` beside it); returns the shots, the whole window's first."""
    out = Path(png)
    with headless_viewer(size) as viewer:
        viewer.open(rrd)
        shots = [viewer.screenshot(out, time_s=time_s)]
        for name in views:
            slug = "".join(ch if ch.isalnum() else "-" for ch in name.lower()).strip("-")
            shots.append(viewer.screenshot(out.with_name(f"{out.stem}-{slug}.png"), view=name,
                                           settle_s=0.3))
    return shots


__all__ = ["DEFAULT_SIZE", "HeadlessViewer", "Shot", "headless_viewer", "screenshot_rrd",
           "unavailable_reason"]
