"""rocas's servers listen on loopback unless the user names an address; a taken port is one line.

The web viewer runs in a real ``rerun`` process here (about a second); its sockets are read
back with psutil."""

from __future__ import annotations

import ipaddress
import socket

import pytest

from rocas.errors import OutputError, UsageError
from rocas.viz.serve import (
    LOOPBACK,
    RerunWebServer,
    bind_warning,
    check_bind_address,
    check_port_free,
    free_port,
    is_loopback,
    url_host,
)


def listening(pid: int) -> list[tuple[str, int]]:
    """The (address, port) pairs a process and its children listen on."""
    psutil = pytest.importorskip("psutil")
    root = psutil.Process(pid)
    found = []
    for p in [root, *root.children(recursive=True)]:
        try:
            conns = p.net_connections(kind="inet")
        except (psutil.NoSuchProcess, psutil.AccessDenied):
            continue
        found += [(c.laddr.ip, c.laddr.port) for c in conns if c.status == psutil.CONN_LISTEN]
    return found


def on_loopback(ip: str) -> bool:
    addr = ipaddress.ip_address(ip)
    return (getattr(addr, "ipv4_mapped", None) or addr).is_loopback


def test_loopback_and_bind_addresses():
    assert is_loopback("127.0.0.1") and is_loopback("::1") and is_loopback("localhost")
    assert not is_loopback("0.0.0.0") and not is_loopback("192.0.2.7")
    assert bind_warning("127.0.0.1") is None
    assert "anyone who can reach this machine" in bind_warning("0.0.0.0")
    assert check_bind_address("localhost") == LOOPBACK and check_bind_address("[::1]") == "::1"
    with pytest.raises(UsageError, match="not an IP address"):
        check_bind_address("evil.example")
    assert url_host("0.0.0.0") == LOOPBACK and url_host("::1") == "[::1]"


def test_a_taken_port_is_one_line():
    with socket.socket() as s:
        s.bind((LOOPBACK, 0))
        s.listen()
        port = s.getsockname()[1]
        with pytest.raises(OutputError, match=rf"cannot listen on 127.0.0.1:{port}: already in use") as e:
            check_port_free(LOOPBACK, port, "--web-port")
        assert "--web-port" in e.value.hint
    check_port_free(LOOPBACK, 0, "--web-port")  # any port: nothing to check


def test_the_web_viewer_and_its_data_listen_on_loopback(tmp_path):
    import rerun as rr

    rrd = tmp_path / "t.rrd"
    rec = rr.RecordingStream("t")
    rec.save(rrd)
    rec.log("x", rr.Points3D([[0, 0, 0]]))
    rec.disconnect()
    server = RerunWebServer(LOOPBACK, 0, free_port(), sources=[str(rrd)])
    server.start()
    try:
        found = listening(server.pid)
        assert {server.web_port, server.grpc_port} <= {port for _, port in found}
        assert all(on_loopback(ip) for ip, _ in found), found
        assert server.grpc_url == f"rerun+http://127.0.0.1:{server.grpc_port}/proxy"
        with socket.create_connection((LOOPBACK, server.web_port), timeout=2):
            pass
        pid = server.pid
    finally:
        server.stop()
    psutil = pytest.importorskip("psutil")
    assert not psutil.pid_exists(pid) or psutil.Process(pid).status() == psutil.STATUS_ZOMBIE
    with pytest.raises(OSError):
        socket.create_connection((LOOPBACK, server.web_port), timeout=1).close()
    server.stop()  # idempotent


def test_a_web_viewer_port_in_use_is_refused_before_starting():
    with socket.socket() as s:
        s.bind((LOOPBACK, 0))
        s.listen()
        server = RerunWebServer(LOOPBACK, s.getsockname()[1], sources=["http://127.0.0.1:1/x.rrd"])
        with pytest.raises(OutputError, match="already in use"):
            server.start()
        assert server.pid is None
