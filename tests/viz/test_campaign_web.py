"""The campaign page's server: on loopback, refuses other hosts' names (DNS rebinding), and a
campaign folder someone else made cannot make it read or write outside that folder."""

from __future__ import annotations

import http.client
import json

import pytest
from test_serve import listening, on_loopback

from rocas.viz.campaign_web import CampaignServer, host_allowed, read_campaign


def _get(srv: CampaignServer, path: str, host: str | None = None) -> tuple[int, bytes]:
    conn = http.client.HTTPConnection("127.0.0.1", srv.port, timeout=30)
    try:
        conn.putrequest("GET", path, skip_host=True)
        conn.putheader("Host", host or f"127.0.0.1:{srv.port}")
        conn.endheaders()
        r = conn.getresponse()
        return r.status, r.read()
    finally:
        conn.close()


@pytest.fixture
def hostile_campaign(tmp_path):
    d = tmp_path / "campaign"
    d.mkdir()
    outside = tmp_path / "outside"
    outside.mkdir()
    (outside / "secret.rrd").write_bytes(b"secret")
    names = ["../outside/secret", str(outside / "secret"), "..", "no_run_dir", "[/bold]<b>x</b>"]
    (d / "campaign.json").write_text(json.dumps(
        {"accidents": [{"name": n} for n in names], "groups": [], "failed": []}))
    return d, outside


@pytest.fixture
def server(hostile_campaign):
    srv = CampaignServer(hostile_campaign[0], port=0, web_viewer_port=0)
    srv.start()
    yield srv
    srv.stop()


def test_everything_listens_on_loopback(server):
    import os

    assert server._httpd.server_address[0] == "127.0.0.1"
    assert server.url == f"http://127.0.0.1:{server.port}/"
    found = listening(os.getpid()) + listening(server._viewer.pid)
    ports = {p for _, p in found}
    assert {server.port, server.web_viewer_port} <= ports
    assert all(on_loopback(ip) for ip, p in found if p in (server.port, server.web_viewer_port))
    assert all(on_loopback(ip) for ip, _ in listening(server._viewer.pid))
    status, body = _get(server, "/rerun/")  # Rerun's web viewer, passed through
    assert status == 200 and b"<html" in body.lower()


def test_other_hosts_names_are_refused(server):
    assert _get(server, "/campaign.json")[0] == 200
    assert _get(server, "/campaign.json", f"localhost:{server.port}")[0] == 200
    status, body = _get(server, "/campaign.json", f"attacker.example:{server.port}")
    assert status == 421 and b"accidents" not in body
    assert _get(server, "/rerun/", "attacker.example")[0] == 421
    assert host_allowed("[::1]:8080") and host_allowed("127.0.0.1")
    assert not host_allowed(None) and not host_allowed("rebind.127.0.0.1.nip.io:8080")


def test_names_from_the_index_never_leave_the_folder(server, hostile_campaign, capsys):
    d, outside = hostile_campaign
    for name in ("..%2Foutside%2Fsecret", "%2E%2E", "no_run_dir", "not_listed",
                 "%2F" + str(outside / "secret").lstrip("/").replace("/", "%2F")):
        status, body = _get(server, f"/rrd/{name}.rrd")
        assert status == 404, (name, status)
        assert b"secret" not in body
    assert (outside / "secret.rrd").read_bytes() == b"secret"
    assert sorted(p.name for p in outside.iterdir()) == ["secret.rrd"]
    assert not (d / "rrd").exists() or list((d / "rrd").iterdir()) == []
    assert "Traceback" not in capsys.readouterr().err  # no handler thread died


def test_a_campaign_json_that_is_not_an_object_is_refused(tmp_path):
    from rocas.errors import InputError

    (tmp_path / "campaign.json").write_text("[" * 100000)
    with pytest.raises(InputError, match="campaign.json"):
        read_campaign(tmp_path)
    (tmp_path / "campaign.json").write_text("[1, 2]")
    with pytest.raises(InputError, match="not a JSON object"):
        read_campaign(tmp_path)


def test_a_page_port_in_use_is_one_line(hostile_campaign):
    import socket

    from rocas.errors import OutputError

    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        s.listen()
        srv = CampaignServer(hostile_campaign[0], port=s.getsockname()[1], web_viewer_port=0)
        with pytest.raises(OutputError, match="already in use") as e:
            srv.start()
        assert "--page-port" in e.value.hint
    srv.stop()


def test_an_rrd_an_earlier_rocas_cached_is_written_again(small_campaign):
    from rocas.viz.campaign_web import RRD_LAYOUT

    out, campaign = small_campaign
    name = campaign["accidents"][0]["name"]
    cached = out / "rrd" / f"{name}.rrd"
    cached.parent.mkdir(exist_ok=True)
    cached.write_bytes(b"RRF2 written by an earlier rocas, its blueprint not active")
    (out / "rrd" / f"{name}.rrd.layout").unlink(missing_ok=True)
    srv = CampaignServer(out, port=0, web_viewer_port=0)
    srv.start()
    try:
        status, body = _get(srv, f"/rrd/{name}.rrd")
        assert status == 200 and body.startswith(b"RRF2") and b"earlier rocas" not in body
        assert (out / "rrd" / f"{name}.rrd.layout").read_text().strip() == RRD_LAYOUT
        again_status, again = _get(srv, f"/rrd/{name}.rrd")  # now kept as it is
        assert again_status == 200 and again == body
    finally:
        srv.stop()
