"""``rocas view --web CAMPAIGN_DIR``: the browser view of a campaign (the page in ``viewer/``).

One HTTP server on localhost serves, all from one origin:

- ``/``, ``/app.js``, ``/style.css``: the static page of the repository's ``viewer/`` folder
  (:func:`viewer_dir`);
- ``/campaign.json``: the campaign's groups and accidents (``rocas triage``'s file);
- ``/rrd/<accident>.rrd``: the accident's analysis as a Rerun recording, written on its first
  request into ``CAMPAIGN_DIR/rrd/`` (:func:`rocas.viz.analysis.write_run_dir_rrd`) and kept;
- ``/rerun/...``: Rerun's web viewer, the one rerun-sdk ships (so always the version of the
  installed rerun-sdk, 0.41), passed through from :func:`rerun.serve_web_viewer`; its page's
  links to web fonts are left out, so it loads with no network.

The page loads ``/rerun/?url=<origin>/rrd/<accident>.rrd`` in a frame for the selected accident.
"""

from __future__ import annotations

import json
import re
import threading
import urllib.error
import urllib.request
from http import HTTPStatus
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer
from pathlib import Path
from typing import Any

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
    path = campaign_dir / "campaign.json"
    try:
        return json.loads(path.read_text(encoding="utf-8"))
    except FileNotFoundError:
        raise InputError(f"{campaign_dir}: no campaign.json", "run rocas triage first") from None
    except (OSError, ValueError) as exc:
        raise InputError(f"{path}: cannot read the campaign: {exc}") from None


class CampaignServer:
    """The server of one campaign (see the module docstring); :meth:`start` serves in a thread.

    Attributes:
        port: the page's port (0 before :meth:`start` with port 0: any free one).
        url: the page's address once started.
    """

    def __init__(self, campaign_dir: str | Path, port: int = 8080, web_viewer_port: int = 9090) -> None:
        self.campaign_dir = Path(campaign_dir)
        self.campaign = read_campaign(self.campaign_dir)
        self.page = viewer_dir()
        self.port = port
        self.web_viewer_port = web_viewer_port
        self._httpd: ThreadingHTTPServer | None = None
        self._lock = threading.Lock()  # one .rrd written at a time

    @property
    def url(self) -> str:
        return f"http://127.0.0.1:{self.port}/"

    def start(self) -> None:
        import rerun as rr

        rr.serve_web_viewer(web_port=self.web_viewer_port, open_browser=False)
        server = self

        class Handler(BaseHTTPRequestHandler):
            def do_GET(self) -> None:  # noqa: N802 - http.server's name
                server._get(self)

            def log_message(self, format: str, *args: Any) -> None:  # noqa: A002
                pass

        self._httpd = ThreadingHTTPServer(("127.0.0.1", self.port), Handler)
        self.port = self._httpd.server_address[1]
        threading.Thread(target=self._httpd.serve_forever, daemon=True).start()

    def stop(self) -> None:
        if self._httpd is not None:
            self._httpd.shutdown()
            self._httpd.server_close()
            self._httpd = None

    # --- requests -----------------------------------------------------------------------------

    def _get(self, h: BaseHTTPRequestHandler) -> None:
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
        names = {a["name"] for a in self.campaign.get("accidents", [])}
        if name not in names:
            return _send(h, f"no analysed accident {name!r}".encode(), "text/plain", HTTPStatus.NOT_FOUND)
        out = self.campaign_dir / "rrd" / f"{name}.rrd"
        with self._lock:
            if not out.exists():
                from rocas.viz.analysis import write_run_dir_rrd

                out.parent.mkdir(exist_ok=True)
                write_run_dir_rrd(out, self.campaign_dir / "runs" / name)
        _send(h, out.read_bytes(), "application/octet-stream")

    def _rerun(self, h: BaseHTTPRequestHandler, rest: str) -> None:
        try:
            with urllib.request.urlopen(f"http://127.0.0.1:{self.web_viewer_port}{rest}") as r:
                body = r.read()
                ctype = r.headers.get("Content-Type", "application/octet-stream")
                extra = {k: v for k, v in r.headers.items()
                         if k.lower() in ("content-encoding", "rerun-final-length")}
        except urllib.error.HTTPError as exc:
            return _send(h, exc.read(), "text/plain", HTTPStatus(exc.code))
        if rest.split("?", 1)[0] in ("/", "/index.html"):
            body = _WEB_FONTS.sub(b"", body)
        _send(h, body, ctype, extra=extra)


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
