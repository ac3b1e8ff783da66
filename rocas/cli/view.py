"""``rocas view RUN_DIR | RECORDING.mcap``: the Rerun visual debugger.

Opens the native viewer when a display is available; with ``--web`` (or without a display)
serves Rerun's web viewer on localhost and prints its address until Ctrl-C. ``--rrd`` also
writes the recording (with its default layout) to a file; ``--no-viewer`` only writes it.
"""

from __future__ import annotations

import argparse
import os
import sys
import tempfile
import time
from pathlib import Path

from rocas._fs import check_writable
from rocas.cli.console import Env
from rocas.errors import InputError, UsageError

HELP = "open a recording or an analysis run directory in the Rerun viewer"


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument(
        "source",
        metavar="RUN_DIR|RECORDING.mcap",
        help="a directory written by 'rocas analyze', or one MCAP recording",
    )
    p.add_argument("--rrd", metavar="OUT.rrd", help="write the Rerun recording to this file")
    p.add_argument("--web", action="store_true", help="serve the web viewer instead of the native one")
    p.add_argument("--no-viewer", action="store_true", help="only write --rrd; open no viewer")
    p.add_argument("--web-port", type=int, default=9090, help="web viewer port (default 9090)")
    p.add_argument("--grpc-port", type=int, default=9876, help="gRPC data port (default 9876)")


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

    if source.is_dir():
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
    keep = Path(args.rrd) if args.rrd else None
    if keep is not None:
        check_writable(keep)
    tmpdir = None
    if keep is None:
        tmpdir = tempfile.TemporaryDirectory(prefix="rocas-view-")
        out = Path(tmpdir.name) / "view.rrd"
    else:
        out = keep
    try:
        summary, warnings = write_rrd(source, out)
        for line in warnings:
            env.warn(line)
        if keep is not None:
            env.out().print(f"Rerun recording: {keep} ({summary})")
        if args.no_viewer:
            return 0
        if args.web or not has_display():
            return _serve_web(out, args, env)
        _spawn_native(out, args)
        env.out().print("Opened the Rerun viewer.")
        return 0
    finally:
        if tmpdir is not None:
            tmpdir.cleanup()


def _spawn_native(out: Path, args: argparse.Namespace) -> None:
    import subprocess

    from rocas.errors import RocasError

    try:
        subprocess.Popen(
            ["rerun", "--port", str(args.grpc_port), str(out)],
            start_new_session=True,
            stdout=subprocess.DEVNULL,
            stderr=subprocess.DEVNULL,
        )
    except FileNotFoundError:
        raise RocasError(
            "the 'rerun' viewer executable is not on PATH",
            hint="pip install rerun-sdk, or use --rrd and open the file elsewhere",
        ) from None
    if out.parent.name.startswith("rocas-view-"):
        time.sleep(2.0)  # let the viewer read the temporary file before it is removed


def _serve_web(out: Path, args: argparse.Namespace, env: Env) -> int:
    import rerun as rr

    rec = rr.RecordingStream("rocas", recording_id=f"rocas-view-{out.stem}")
    url = rec.serve_grpc(grpc_port=args.grpc_port)
    rr.serve_web_viewer(web_port=args.web_port, open_browser=False, connect_to=url)
    rec.log_file_from_path(out)
    address = f"http://localhost:{args.web_port}/?url={url}"
    env.out().print(f"Rerun web viewer: {address}")
    env.out().print("Serving until Ctrl-C.")
    env.stdout.flush()
    try:
        while True:
            time.sleep(1.0)
    except KeyboardInterrupt:
        rec.disconnect()
        return 0
