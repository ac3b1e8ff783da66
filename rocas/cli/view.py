"""``rocas view RUN_DIR | RECORDING.mcap``: the Rerun visual debugger.

Opens the native viewer when a display is available (it is given a file it may read whenever
it likes: rocas never removes it under the viewer, and says whether the viewer started or
failed); with ``--web`` (or without a display) serves Rerun's web viewer on localhost and
prints its address until Ctrl-C. ``--rrd`` also
writes the recording (with its default layout) to a file; ``--no-viewer`` only writes it.
"""

from __future__ import annotations

import argparse
import os
import sys
import tempfile
import time
from collections.abc import Callable
from pathlib import Path

from rocas._fs import check_writable
from rocas.cli.console import Env
from rocas.errors import InputError, UsageError

HELP = "open a recording or an analysis run directory in the Rerun viewer"


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument(
        "source",
        metavar="RUN_DIR|RECORDING.mcap",
        help="a directory written by 'rocas analyze', or one recording (MCAP, ROS 1 bag, "
             "rosbag2, Cyber RT record)",
    )
    p.add_argument("--rrd", metavar="OUT.rrd", help="write the Rerun recording to this file")
    p.add_argument("--web", action="store_true", help="serve the web viewer instead of the native one")
    p.add_argument("--no-viewer", action="store_true", help="only write --rrd; open no viewer")
    p.add_argument("--web-port", type=int, default=9090, help="web viewer port (default 9090)")
    p.add_argument("--grpc-port", type=int, default=9876, help="gRPC data port (default 9876)")
    p.add_argument("--page-port", type=int, default=8080,
                   help="with a campaign directory: the campaign page's port (default 8080)")


def has_display(environ: dict[str, str] | None = None) -> bool:
    """True when a native window can be opened (X11/Wayland; always on macOS and Windows)."""
    env = os.environ if environ is None else environ
    if sys.platform in ("darwin", "win32"):
        return True
    return bool(env.get("DISPLAY") or env.get("WAYLAND_DISPLAY"))


def write_rrd(source: Path, out: Path) -> tuple[str, list[str]]:
    """Write the ``.rrd`` of ``source`` (run directory or recording).

    Returns:
        What it showed (one line), and the warnings of the recordings it read (damage,
        truncation, skipped channels; one line each, without the ``rocas: warning:`` prefix).
    """
    from rocas.viz.analysis import write_recording_rrd, write_run_dir_rrd

    if source.is_dir() and not (source / "metadata.yaml").is_file():  # not a rosbag2 directory
        contents = write_run_dir_rrd(out, source)
        shown = [n for n in ("accident", "reference", "fixed") if n in contents]
        parts = [f"executions: {', '.join(shown)}"]
        if contents.get("searches"):
            parts.append(f"searches: {', '.join(contents['searches'])}")
        if "verdict_md" in contents:
            parts.append("verdict")
        return "; ".join(parts), [w for n in shown for w in contents[n].warnings]
    ex, topics = write_recording_rrd(out, source)
    found = ", ".join(f"{k} from {v}" for k, v in ex.sources.items()) or "no scene channels"
    return f"{found}; {len(topics)} channels through Rerun's MCAP importer", list(ex.warnings)


def run(args: argparse.Namespace, env: Env) -> int:
    source = Path(args.source)
    if not source.exists():
        raise InputError(f"{source}: no such file or directory")
    if args.no_viewer and not args.rrd:
        raise UsageError("--no-viewer needs --rrd OUT.rrd")
    if source.is_dir() and (source / "campaign.json").exists():
        return _serve_campaign(source, args, env)
    keep = Path(args.rrd) if args.rrd else None
    if keep is not None:
        check_writable(keep)
    native = not args.no_viewer and not args.web and has_display()
    tmpdir = None
    if keep is not None:
        out = keep
    elif native:
        # the viewer reads the file whenever it gets to it: it is left for it, never removed
        # under it (the system's temporary folder is cleaned as usual)
        out = Path(tempfile.mkdtemp(prefix="rocas-view-")) / f"{source.stem or 'view'}.rrd"
    else:
        tmpdir = tempfile.TemporaryDirectory(prefix="rocas-view-")
        out = Path(tmpdir.name) / "view.rrd"
    try:
        with env.progress(f"Writing the Rerun recording of {source.name}"):
            summary, warnings = write_rrd(source, out)
        for line in warnings:
            env.warn(line)
        if keep is not None:
            env.out().print(f"Rerun recording: {keep} ({summary})")
        if args.no_viewer:
            return 0
        if not native:
            return _serve_web(out, args, env)
        pid, running = _spawn_native(out, args)
        left = "" if keep is not None else f"; it reads {out}, which is left for it"
        if running:
            env.out().print(f"Started the Rerun viewer (process {pid}){left}.")
        else:
            env.out().print(f"The Rerun viewer (process {pid}) took the file and exited at once "
                            f"with status 0 (a viewer already open may show it){left}.")
        return 0
    finally:
        if tmpdir is not None:
            tmpdir.cleanup()


#: How long a viewer that fails at once (no GPU, a broken install) is waited for [s]; a viewer
#: still running then is reported as started.
SPAWN_CHECK_S = 1.0


def _spawn_native(out: Path, args: argparse.Namespace) -> tuple[int, bool]:
    """Start the native viewer on ``out``: its process id, and whether it is still running
    after :data:`SPAWN_CHECK_S`. Raises if it fails at once."""
    import subprocess

    from rocas.errors import RocasError

    try:
        proc = subprocess.Popen(
            ["rerun", "--port", str(args.grpc_port), str(out)],
            start_new_session=True,
            stdout=subprocess.DEVNULL,
            stderr=subprocess.PIPE,
        )
    except FileNotFoundError:
        raise RocasError(
            "the 'rerun' viewer executable is not on PATH",
            hint="pip install rerun-sdk, or use --rrd and open the file elsewhere",
        ) from None
    try:
        code = proc.wait(timeout=SPAWN_CHECK_S)
    except subprocess.TimeoutExpired:
        if proc.stderr is not None:
            proc.stderr.close()  # the viewer keeps running on its own
        return proc.pid, True
    err = proc.stderr.read().decode(errors="replace").strip() if proc.stderr else ""
    last = err.splitlines()[-1] if err else "no message"
    if code == 0:
        return proc.pid, False
    raise RocasError(
        f"the Rerun viewer exited at once with status {code}: {last}",
        hint="use --web, or --rrd OUT.rrd and open the file elsewhere",
    )


def _serve_web(out: Path, args: argparse.Namespace, env: Env) -> int:
    from rocas.viz.stream import new_recording_id  # noqa: I001 - first: it quiets Rerun's logs
    import rerun as rr

    rec = rr.RecordingStream("rocas", recording_id=new_recording_id("view"))
    url = rec.serve_grpc(grpc_port=args.grpc_port)
    rr.serve_web_viewer(web_port=args.web_port, open_browser=False, connect_to=url)
    rec.log_file_from_path(out)
    address = f"http://localhost:{args.web_port}/?url={url}"
    return _serve_until_interrupt(env, f"Rerun web viewer: {address}", rec.disconnect)


def _serve_campaign(campaign_dir: Path, args: argparse.Namespace, env: Env) -> int:
    """A ``rocas triage`` directory: its browser view (viewer/), served until Ctrl-C."""
    from rocas.viz.campaign_web import CampaignServer

    if not args.web:
        raise UsageError(f"{campaign_dir} is a campaign: it is shown in the browser",
                         f"rocas view --web {campaign_dir}")
    server = CampaignServer(campaign_dir, port=args.page_port, web_viewer_port=args.web_port)
    server.start()
    return _serve_until_interrupt(env, f"Campaign view: {server.url}", server.stop)


def _serve_until_interrupt(env: Env, where: str, stop: Callable[[], object]) -> int:
    """Say where the page is, then wait for Ctrl-C and ``stop`` the server (exit 0)."""
    env.out().print(where)
    env.out().print("Serving until Ctrl-C.")
    env.stdout.flush()
    try:
        while True:
            time.sleep(1.0)
    except KeyboardInterrupt:
        stop()
        return 0
