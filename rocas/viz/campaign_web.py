"""``rocas view --web CAMPAIGN_DIR``: the browser view of a campaign (the page in ``viewer/``).

One HTTP server, on 127.0.0.1 unless the user names an address (``rocas view --bind``), serves,
all from one origin:

- ``/``, ``/app.js``, ``/style.css``: the static page of the repository's ``viewer/`` folder
  (:func:`viewer_dir`);
- ``/campaign.json``: the campaign's groups and accidents (``rocas triage``'s file);
- ``/rrd/<accident>.rrd``: the accident's analysis as a Rerun recording, written on its first
  request into ``CAMPAIGN_DIR/rrd/`` (:func:`rocas.viz.analysis.write_run_dir_rrd`) and kept
  (written again when an earlier rocas wrote it with another layout: :data:`RRD_LAYOUT`);
- ``/rerun/...``: Rerun's web viewer, the one rerun-sdk ships (so always the version of the
  installed rerun-sdk, 0.41), passed through from a ``rerun --serve-web`` process on
  127.0.0.1 (:class:`rocas.viz.serve.RerunWebServer`); its page's links to web fonts are left
  out, so it loads with no network.

The page loads ``/rerun/?url=<origin>/rrd/<accident>.rrd`` in a frame for the selected accident.

A campaign folder is someone else's data: only accidents its ``campaign.json`` lists are served,
and only when the name is one harmless path component whose run directory lies inside the
folder (:func:`rocas._fs.safe_component`, :func:`rocas._fs.inside`). A request whose ``Host``
is a name other than ``localhost`` is refused (421): a web page elsewhere cannot reach the server
by pointing its own name at 127.0.0.1 (DNS rebinding).
"""

from __future__ import annotations

import ipaddress
import json
import re
import socket
import threading
import urllib.error
import urllib.request
from http import HTTPStatus
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer
from pathlib import Path
from typing import Any

from rocas._fs import inside, is_safe_component
from rocas.errors import InputError, RocasError

_PAGE_FILES = {"/": "index.html", "/index.html": "index.html", "/app.js": "app.js",
               "/style.css": "style.css"}
_TYPES = {".html": "text/html; charset=utf-8", ".js": "text/javascript; charset=utf-8",
          ".css": "text/css; charset=utf-8"}
#: the web viewer page's references to fonts on the web (no network: they would only fail)
_WEB_FONTS = re.compile(rb"<link[^>]*fonts\.(?:googleapis|gstatic)\.com[^>]*>", re.S)


def viewer_dir() -> Path:
    """The browser view's page: the repository's ``viewer/`` folder, which the package reaches
    as ``rocas/viz/page`` (a link to it in a checkout or an editable install; the files
    themselves in a wheel or an sdist)."""
    from importlib import resources

    d = Path(str(resources.files("rocas.viz") / "page"))
    if not (d / "index.html").is_file():
        raise RocasError(f"the browser view's page is not found (looked in {d})",
                         "reinstall rocas: its wheel carries the page as rocas/viz/page")
    return d


def read_campaign(campaign_dir: Path) -> dict[str, Any]:
    from rocas._limits import load_json_file

    path = campaign_dir / "campaign.json"
    if not path.exists():
        raise InputError(f"{campaign_dir}: no campaign.json", "run rocas triage first")
    campaign = load_json_file(path, what="campaign")
    if not isinstance(campaign, dict):
        raise InputError(f"{path}: cannot read the campaign: not a JSON object",
                         "run rocas triage again")
    return campaign


def host_allowed(host_header: str | None) -> bool:
    """Whether a request's ``Host`` may be served: an IP address or ``localhost`` (with any
    port). A DNS name pointed at this machine by someone else's page is refused."""
    if not host_header:
        return False
    host = host_header.strip()
    if host.startswith("["):  # [v6]:port
        host = host[1:host.find("]")] if "]" in host else host
    elif host.count(":") == 1:
        host = host.rsplit(":", 1)[0]
    if host.lower() == "localhost":
        return True
    try:
        ipaddress.ip_address(host)
    except ValueError:
        return False
    return True


class CampaignServer:
    """The server of one campaign (see the module docstring); :meth:`start` serves in a thread.

    Attributes:
        port: the page's port (0 before :meth:`start` with port 0: any free one).
        url: the page's address once started.
    """

    def __init__(self, campaign_dir: str | Path, port: int = 8080, web_viewer_port: int = 9090,
                 host: str = "127.0.0.1") -> None:
        self.campaign_dir = Path(campaign_dir)
        self.campaign = read_campaign(self.campaign_dir)
        self.page = viewer_dir()
        self.host = host
        self.port = port
        self.web_viewer_port = web_viewer_port
        self._httpd: ThreadingHTTPServer | None = None
        self._viewer: Any = None
        self._lock = threading.Lock()  # one .rrd written at a time

    @property
    def url(self) -> str:
        from rocas.viz.serve import url_host

        return f"http://{url_host(self.host)}:{self.port}/"

    def start(self) -> None:
        """Listen on :attr:`host` and start Rerun's web viewer on 127.0.0.1 (only this server
        reaches it). A port in use is an :class:`~rocas.errors.OutputError` in one line."""
        from rocas.viz.serve import LOOPBACK, RerunWebServer, port_error

        server = self

        class Handler(BaseHTTPRequestHandler):
            def do_GET(self) -> None:  # noqa: N802 - http.server's name
                server._get(self)

            def log_message(self, format: str, *args: Any) -> None:  # noqa: A002
                pass

        class Server(ThreadingHTTPServer):
            address_family = socket.AF_INET6 if ":" in self.host else socket.AF_INET
            daemon_threads = True

        try:
            self._httpd = Server((self.host, self.port), Handler)
        except OSError as exc:
            raise port_error(self.host, self.port, "--page-port", exc) from None
        self.port = self._httpd.server_address[1]
        # the web viewer is given the page's address as its source: it then serves the viewer
        # alone, with no gRPC proxy of its own
        self._viewer = RerunWebServer(LOOPBACK, self.web_viewer_port, sources=[self.url])
        try:
            self._viewer.start()
        except BaseException:
            self._httpd.server_close()
            self._httpd = None
            raise
        self.web_viewer_port = self._viewer.web_port
        threading.Thread(target=self._httpd.serve_forever, daemon=True).start()

    def stop(self) -> None:
        if self._httpd is not None:
            self._httpd.shutdown()
            self._httpd.server_close()
            self._httpd = None
        if self._viewer is not None:
            self._viewer.stop()
            self._viewer = None

    # --- requests -----------------------------------------------------------------------------

    def _get(self, h: BaseHTTPRequestHandler) -> None:
        if not host_allowed(h.headers.get("Host")):
            return _send(h, b"unknown host: open the page at the address rocas printed",
                         "text/plain", HTTPStatus.MISDIRECTED_REQUEST)
        path = h.path.split("?", 1)[0]
        if path in _PAGE_FILES:
            f = self.page / _PAGE_FILES[path]
            return _send(h, f.read_bytes(), _TYPES[f.suffix])
        if path == "/campaign.json":
            return _send(h, json.dumps(self.campaign).encode(), "application/json")
        if path.startswith("/rrd/") and path.endswith(".rrd"):
            return self._rrd(h, urllib.request.unquote(path[len("/rrd/"):-len(".rrd")]))
        if path == "/rerun" or path.startswith("/rerun/"):
            return self._rerun(h, h.path[len("/rerun"):] or "/")
        _send(h, b"not found", "text/plain", HTTPStatus.NOT_FOUND)

    def _rrd(self, h: BaseHTTPRequestHandler, name: str) -> None:
        names = {a.get("name") for a in self.campaign.get("accidents", []) if isinstance(a, dict)}
        if name not in names or not is_safe_component(name):
            return _send(h, b"no such analysed accident", "text/plain", HTTPStatus.NOT_FOUND)
        try:
            run_dir = inside(self.campaign_dir, "runs", name)
            out = inside(self.campaign_dir, "rrd", f"{name}.rrd")
            stamp = inside(self.campaign_dir, "rrd", f"{name}.rrd.layout")
            with self._lock:
                if not out.exists() or not _stamped(stamp):
                    from rocas.viz.analysis import write_run_dir_rrd

                    if not run_dir.is_dir():
                        return _send(h, b"the accident's run directory is missing", "text/plain",
                                     HTTPStatus.NOT_FOUND)
                    out.parent.mkdir(exist_ok=True)
                    inside(self.campaign_dir, "rrd")  # rrd/ itself is no link out
                    write_run_dir_rrd(out, run_dir)
                    stamp.write_text(RRD_LAYOUT + "\n", encoding="utf-8")
                body = out.read_bytes()
        except RocasError as exc:
            return _send(h, str(exc).encode(), "text/plain", HTTPStatus.NOT_FOUND)
        except OSError as exc:
            return _send(h, f"cannot write the recording: {exc.strerror or exc}".encode(),
                         "text/plain", HTTPStatus.INTERNAL_SERVER_ERROR)
        _send(h, body, "application/octet-stream")

    def _rerun(self, h: BaseHTTPRequestHandler, rest: str) -> None:
        try:
            with urllib.request.urlopen(f"http://127.0.0.1:{self.web_viewer_port}{rest}") as r:
                body = r.read()
                ctype = r.headers.get("Content-Type", "application/octet-stream")
                extra = {k: v for k, v in r.headers.items()
                         if k.lower() in ("content-encoding", "rerun-final-length")}
        except urllib.error.HTTPError as exc:
            return _send(h, exc.read(), "text/plain", HTTPStatus(exc.code))
        except (urllib.error.URLError, OSError):
            return _send(h, b"Rerun's web viewer does not answer", "text/plain",
                         HTTPStatus.BAD_GATEWAY)
        if rest.split("?", 1)[0] in ("/", "/index.html"):
            body = _WEB_FONTS.sub(b"", body)
        _send(h, body, ctype, extra=extra)


#: what the layout of a cached ``rrd/<accident>.rrd`` is, written beside it (``.rrd.layout``);
#: a file without it, or with another, was written by an earlier rocas (whose blueprint Rerun's
#: web viewer ignored) and is written again. Change it when the .rrd's layout changes.
RRD_LAYOUT = "rocas analysis layout 2: blueprint default and active"


def _stamped(stamp: Path) -> bool:
    try:
        return stamp.read_text(encoding="utf-8").strip() == RRD_LAYOUT
    except (OSError, UnicodeDecodeError):
        return False


def _send(h: BaseHTTPRequestHandler, body: bytes, ctype: str, status: HTTPStatus = HTTPStatus.OK,
          extra: dict[str, str] | None = None) -> None:
    h.send_response(status)
    h.send_header("Content-Type", ctype)
    h.send_header("Content-Length", str(len(body)))
    h.send_header("Cache-Control", "no-cache")
    for k, v in (extra or {}).items():
        h.send_header(k, v)
    h.end_headers()
    try:
        h.wfile.write(body)
    except (BrokenPipeError, ConnectionResetError):
        pass
