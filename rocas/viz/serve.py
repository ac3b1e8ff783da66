"""Where rocas's servers listen: loopback unless the user names an address.

``rocas view --web`` (and ``rocas view`` without a display) and the campaign page start servers:
Rerun's web viewer, Rerun's gRPC data proxy and the page's own HTTP server. Each binds
:data:`LOOPBACK` unless the user gives ``--bind ADDRESS``; a non-loopback address is accepted
with a warning (:func:`bind_warning`). Rerun's SDK offers no bind address, so its servers run in
the ``rerun`` executable (``rerun --serve-web --bind ADDRESS``), in a process group of their own
that :meth:`RerunWebServer.stop` ends whole.
"""

from __future__ import annotations

import contextlib
import ipaddress
import os
import signal
import socket
import subprocess
import tempfile
import time
from collections.abc import Sequence

from rocas.errors import OutputError, RocasError, UsageError

#: the address every server binds unless the user names one
LOOPBACK = "127.0.0.1"

#: how long Rerun's web server may take to start listening [s]
START_TIMEOUT_S = 20.0


def is_loopback(host: str) -> bool:
    """True for an address only this machine reaches (``127.0.0.0/8``, ``::1``, ``localhost``)."""
    if host.lower() == "localhost":
        return True
    try:
        return ipaddress.ip_address(host.strip("[]")).is_loopback
    except ValueError:
        return False


def check_bind_address(host: str) -> str:
    """``host`` if it is an IP address of this machine's form (v4 or v6), else a usage error.

    Host names are refused: what a name resolves to can change under a running server."""
    if host.lower() == "localhost":
        return LOOPBACK
    try:
        ipaddress.ip_address(host.strip("[]"))
    except ValueError:
        raise UsageError(f"--bind {host!r} is not an IP address",
                         "give an address such as 127.0.0.1 (the default) or 0.0.0.0") from None
    return host.strip("[]")


def bind_warning(host: str) -> str | None:
    """The warning to print when a server will listen beyond this machine, else None."""
    if is_loopback(host):
        return None
    return (f"serving on {host}: anyone who can reach this machine on that address can see the "
            "recording (use the default, 127.0.0.1, to keep it to this machine)")


def check_port_free(host: str, port: int, option: str) -> None:
    """Raise :class:`OutputError` (exit 5) in one line if ``port`` on ``host`` is taken."""
    if port == 0:
        return
    family = socket.AF_INET6 if ":" in host else socket.AF_INET
    with socket.socket(family, socket.SOCK_STREAM) as s:
        s.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        try:
            s.bind((host, port))
        except OSError as exc:
            raise port_error(host, port, option, exc) from None


def port_error(host: str, port: int, option: str, exc: OSError) -> OutputError:
    """The one-line error of a port that cannot be listened on."""
    why = "already in use" if exc.errno in (98, 48, 10048) else (exc.strerror or str(exc))
    return OutputError(f"cannot listen on {url_host(host)}:{port}: {why}",
                       f"choose another port with {option}, or stop what listens there")


def free_port(host: str = LOOPBACK) -> int:
    """A port nothing listens on now at ``host`` (for a port given as 0)."""
    family = socket.AF_INET6 if ":" in host else socket.AF_INET
    with socket.socket(family, socket.SOCK_STREAM) as s:
        s.bind((host, 0))
        return int(s.getsockname()[1])


def url_host(host: str) -> str:
    """``host`` as it appears in a URL (an IPv6 address in brackets; any address as loopback's
    when it means every interface, which this machine's browser reaches through loopback)."""
    if host in ("0.0.0.0", "::"):
        return LOOPBACK
    return f"[{host}]" if ":" in host else host


def _connectable(host: str, port: int) -> bool:
    target = LOOPBACK if host in ("0.0.0.0", "::") else host
    try:
        with socket.create_connection((target, port), timeout=0.5):
            return True
    except OSError:
        return False


def rerun_executable() -> str:
    """The Rerun viewer's executable: the binary rerun-sdk ships (``rerun_cli/rerun``) when it
    is there, so that the server is the process rocas started and ends (the ``rerun`` script
    on PATH is a launcher that starts it as a child); else ``rerun`` from PATH."""
    try:
        import rerun_cli
    except ImportError:
        return "rerun"
    binary = os.path.join(os.path.dirname(rerun_cli.__file__), "rerun" + (".exe" if os.name == "nt" else ""))
    return binary if os.path.isfile(binary) and os.access(binary, os.X_OK) else "rerun"


class RerunWebServer:
    """Rerun's web viewer (and, for a file, its gRPC data proxy) in a ``rerun`` process bound to
    one address.

    Attributes:
        host: the bound address.
        web_port: the web viewer's port.
        grpc_port: the gRPC proxy's port (None when the viewer is only pointed at URLs).
        pid: the process id once started.
    """

    def __init__(self, host: str, web_port: int, grpc_port: int | None = None,
                 sources: Sequence[str] = (), web_option: str = "--web-port",
                 grpc_option: str = "--grpc-port") -> None:
        self.host = host
        self.web_port = web_port or free_port(host if host not in ("0.0.0.0", "::") else LOOPBACK)
        self.grpc_port = grpc_port
        self.sources = list(sources)
        self._options = (web_option, grpc_option)
        self._proc: subprocess.Popen[bytes] | None = None
        self._log: tempfile._TemporaryFileWrapper[bytes] | None = None

    def command(self) -> list[str]:
        cmd = [rerun_executable(), "--serve-web", "--bind", self.host,
               "--web-viewer-port", str(self.web_port)]
        if self.grpc_port is not None:
            cmd += ["--port", str(self.grpc_port)]
        return cmd + self.sources

    @property
    def grpc_url(self) -> str:
        return f"rerun+http://{url_host(self.host)}:{self.grpc_port}/proxy"

    @property
    def pid(self) -> int | None:
        return None if self._proc is None else self._proc.pid

    def start(self) -> None:
        """Start the process and wait until the web viewer answers (a port found taken, or a
        process that ends at once, raise in one line)."""
        check_port_free(self.host, self.web_port, self._options[0])
        if self.grpc_port is not None:
            check_port_free(self.host, self.grpc_port, self._options[1])
        self._log = tempfile.NamedTemporaryFile(prefix="rocas-rerun-", suffix=".log")  # noqa: SIM115
        try:
            self._proc = subprocess.Popen(self.command(), stdin=subprocess.DEVNULL,
                                          stdout=subprocess.DEVNULL, stderr=self._log,
                                          start_new_session=True)
        except FileNotFoundError:
            self._close_log()
            raise RocasError("the 'rerun' executable is not on PATH",
                             "pip install rerun-sdk, or use --rrd and open the file elsewhere") from None
        deadline = time.monotonic() + START_TIMEOUT_S
        while not _connectable(self.host, self.web_port):
            code = self._proc.poll()
            if code is not None:
                last = self._last_log_line()
                self._proc = None
                self._close_log()
                raise RocasError(f"Rerun's web viewer exited at once with status {code}: {last}",
                                 "use --rrd OUT.rrd and open the file elsewhere")
            if time.monotonic() > deadline:
                self.stop()
                raise RocasError(f"Rerun's web viewer did not start within {START_TIMEOUT_S:.0f} s",
                                 "use --rrd OUT.rrd and open the file elsewhere")
            time.sleep(0.1)

    def _last_log_line(self) -> str:
        if self._log is None:
            return "no message"
        self._log.seek(0)
        lines = [ln for ln in self._log.read().decode(errors="replace").splitlines() if ln.strip()]
        return lines[-1].strip() if lines else "no message"

    def _close_log(self) -> None:
        if self._log is not None:
            self._log.close()
            self._log = None

    def stop(self) -> None:
        """End the process and what it started (idempotent)."""
        proc, self._proc = self._proc, None
        if proc is None:
            self._close_log()
            return
        with contextlib.suppress(ProcessLookupError, PermissionError):
            os.killpg(proc.pid, signal.SIGTERM)
        # the group, not only the process: ``rerun`` is a launcher whose child is the server
        deadline = time.monotonic() + 5.0
        while _group_alive(proc) and time.monotonic() < deadline:
            time.sleep(0.05)
        if _group_alive(proc):
            with contextlib.suppress(ProcessLookupError, PermissionError):
                os.killpg(proc.pid, signal.SIGKILL)
        proc.wait()
        self._close_log()


def _group_alive(proc: subprocess.Popen[bytes]) -> bool:
    """Whether any process of ``proc``'s group (its id) is still running (``proc`` is reaped
    here when it has ended, so that it does not count as running)."""
    proc.poll()
    try:
        os.killpg(proc.pid, 0)
    except (ProcessLookupError, PermissionError):
        return False
    return True
