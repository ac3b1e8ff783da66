"""``rocas view RUN_DIR | RECORDING.mcap | FILE.rrd``: the Rerun visual debugger.

Opens the native viewer when a display is available (it is given a file it may read whenever
it likes: rocas never removes it under the viewer, and says whether the viewer started or
failed); with ``--web`` (or without a display) serves Rerun's web viewer and its data on
127.0.0.1 (``--bind ADDRESS`` for another, with a warning) and prints its address until Ctrl-C.
``--rrd`` also
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
from rocas.cli.console import Env, safe
from rocas.errors import InputError, UsageError

HELP = "open a recording or an analysis run directory in the Rerun viewer"


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument(
        "source",
        metavar="RUN_DIR|RECORDING|FILE.rrd",
        help="a directory written by 'rocas analyze', one recording (MCAP, ROS 1 bag, "
             "rosbag2, Cyber RT record), or a Rerun recording (.rrd) as it is",
    )
    p.add_argument("--rrd", metavar="OUT.rrd", help="write the Rerun recording to this file")
    p.add_argument("--web", action="store_true", help="serve the web viewer instead of the native one")
    p.add_argument("--no-viewer", action="store_true", help="only write --rrd; open no viewer")
    p.add_argument("--web-port", type=int, default=9090, help="web viewer port (default 9090)")
    p.add_argument("--grpc-port", type=int, default=9876, help="gRPC data port (default 9876)")
    p.add_argument("--page-port", type=int, default=8080,
                   help="with a campaign directory: the campaign page's port (default 8080)")
    p.add_argument("--bind", metavar="ADDRESS", default="127.0.0.1",
                   help="the address the web viewer, its data and the campaign page listen on "
                        "(default 127.0.0.1: this machine only; 0.0.0.0 opens them to the "
                        "network, with a warning)")


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
    from rocas.viz.serve import bind_warning, check_bind_address

    args.bind = check_bind_address(args.bind)
    for port, option in ((args.web_port, "--web-port"), (args.grpc_port, "--grpc-port"),
                         (args.page_port, "--page-port")):
        if not 0 <= port <= 65535:
            raise UsageError(f"{option} {port} is not a port (0-65535)")
    if source.is_dir() and (source / "campaign.json").exists():
        return _serve_campaign(source, args, env)
    keep = Path(args.rrd) if args.rrd else None
    if keep is not None:
        check_writable(keep)
    source = own_view(source)
    if is_rrd_file(source):
        return _view_rrd(source, keep, args, env)
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
        with env.progress(f"Writing the Rerun recording of {safe(source.name)}"):
            summary, warnings = write_rrd(source, out)
        for line in warnings:
            env.warn(line)
        if keep is not None:
            env.out().print(f"Rerun recording: {safe(keep)} ({safe(summary)})", soft_wrap=True)
        if args.no_viewer:
            return 0
        if not native:
            warning = bind_warning(args.bind)
            if warning:
                env.warn(warning)
            return _serve_web(out, args, env)
        pid, running = _spawn_native(out, args)
        left = "" if keep is not None else f"; it reads {safe(out)}, which is left for it"
        if running:
            env.out().print(f"Started the Rerun viewer (process {pid}){left}.", soft_wrap=True)
        else:
            env.out().print(f"The Rerun viewer (process {pid}) took the file and exited at once "
                            f"with status 0 (a viewer already open may show it){left}.",
                            soft_wrap=True)
        return 0
    finally:
        if tmpdir is not None:
            tmpdir.cleanup()


#: the view a stack that analyses in its own world writes into its run directory (the
#: highway stack's ``analyze_recording``): that run directory holds no recordings to draw from
OWN_VIEW = "analysis.rrd"


def own_view(source: Path) -> Path:
    """``RUN_DIR/analysis.rrd`` when ``source`` is the run directory of a stack's own analysis
    (it holds that view and no ``accident.mcap``), else ``source`` itself."""
    if (source.is_dir() and not (source / "accident.mcap").exists()
            and (source / OWN_VIEW).is_file()):
        return source / OWN_VIEW
    return source


#: the first bytes of every Rerun recording file (an .rrd or a blueprint .rbl)
RRD_MAGIC = b"RRF2"


def is_rrd_file(source: Path) -> bool:
    """Whether ``source`` is a file that is a Rerun recording: named ``.rrd`` (or ``.rbl``).

    Raises:
        InputError: it is named so but does not start as one (a file renamed, a download cut).
    """
    if not source.is_file() or source.suffix.lower() not in (".rrd", ".rbl"):
        return False
    try:
        with open(source, "rb") as f:
            head = f.read(len(RRD_MAGIC))
    except OSError as exc:
        raise InputError(f"cannot read {source}: {exc.strerror or exc}", "check the path") from None
    if head != RRD_MAGIC:
        raise InputError(f"{source}: not a Rerun recording (it does not start as an .rrd does)",
                         "give an .rrd written by rocas or Rerun")
    return True


def _view_rrd(source: Path, keep: Path | None, args: argparse.Namespace, env: Env) -> int:
    """An existing ``.rrd``: shown as it is (its own layout), natively or in the browser;
    ``--rrd`` copies it."""
    import shutil

    from rocas._fs import atomic_path
    from rocas.viz.serve import bind_warning

    if keep is not None:
        with atomic_path(keep) as tmp:
            shutil.copyfile(source, tmp)
        env.out().print(f"Rerun recording: {safe(keep)} (a copy of {safe(source)})", soft_wrap=True)
    if args.no_viewer:
        return 0
    if args.web or not has_display():
        warning = bind_warning(args.bind)
        if warning:
            env.warn(warning)
        return _serve_web(source.resolve(), args, env)
    pid, running = _spawn_native(source.resolve(), args)
    if running:
        env.out().print(f"Started the Rerun viewer (process {pid}).", soft_wrap=True)
    else:
        env.out().print(f"The Rerun viewer (process {pid}) took the file and exited at once with "
                        "status 0 (a viewer already open may show it).", soft_wrap=True)
    return 0


#: How long a viewer that fails at once (no GPU, a broken install) is waited for [s]; a viewer
#: still running then is reported as started.
SPAWN_CHECK_S = 1.0


def _spawn_native(out: Path, args: argparse.Namespace) -> tuple[int, bool]:
    """Start the native viewer on ``out``: its process id, and whether it is still running
    after :data:`SPAWN_CHECK_S`. Raises if it fails at once."""
    import subprocess

    from rocas.errors import RocasError
    from rocas.viz.serve import LOOPBACK, check_port_free

    # the native viewer also listens for SDKs on --grpc-port: on loopback, never the network
    check_port_free(LOOPBACK, args.grpc_port, "--grpc-port")
    try:
        proc = subprocess.Popen(
            ["rerun", "--bind", LOOPBACK, "--port", str(args.grpc_port), str(out)],
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
    """Rerun's web viewer and its gRPC data proxy, both on ``--bind``, serving ``out``."""
    from urllib.parse import quote

    from rocas.viz.serve import RerunWebServer, free_port, url_host

    grpc_port = args.grpc_port or free_port(args.bind if args.bind not in ("0.0.0.0", "::")
                                            else "127.0.0.1")
    server = RerunWebServer(args.bind, args.web_port, grpc_port, sources=[str(out)])
    server.start()
    try:
        address = (f"http://{url_host(args.bind)}:{server.web_port}/"
                   f"?url={quote(server.grpc_url, safe=':/')}")
        return _serve_until_interrupt(env, f"Rerun web viewer: {address}", server.stop)
    finally:
        server.stop()


def _serve_campaign(campaign_dir: Path, args: argparse.Namespace, env: Env) -> int:
    """A ``rocas triage`` directory: its browser view (viewer/), served until Ctrl-C."""
    from rocas.viz.campaign_web import CampaignServer

    if not args.web:
        raise UsageError(f"{campaign_dir} is a campaign: it is shown in the browser",
                         f"rocas view --web {campaign_dir}")
    from rocas.viz.serve import bind_warning

    server = CampaignServer(campaign_dir, port=args.page_port, web_viewer_port=args.web_port,
                            host=args.bind)
    warning = bind_warning(args.bind)
    if warning:
        env.warn(warning)
    server.start()
    return _serve_until_interrupt(env, f"Campaign view: {server.url}", server.stop)


def _serve_until_interrupt(env: Env, where: str, stop: Callable[[], object]) -> int:
    """Say where the page is, then wait for Ctrl-C and ``stop`` the server (exit 0)."""
    try:  # Ctrl-C as soon as the address is out (a script that read it) stops as cleanly
        env.out().print(safe(where), soft_wrap=True)
        env.out().print("Serving until Ctrl-C.")
        env.stdout.flush()
        while True:
            time.sleep(1.0)
    except KeyboardInterrupt:
        stop()
        return 0
