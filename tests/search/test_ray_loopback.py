"""A private local Ray (``--executor ray`` without an address) is reachable from this machine
only: every socket its processes listen on is on loopback, and it demands Ray's token.

The Ray runs in a child process (as tests/search/test_ray_child.py does, a dying local Ray ends
its driver); the child lists the listening sockets of itself and every process it started."""

from __future__ import annotations

import ipaddress
import json
import os
import subprocess
import sys
import types
from pathlib import Path

import pytest

from rocas.search import ray_executor
from rocas.search.ray_executor import private_ray_environment, ray_version

ROOT = Path(__file__).resolve().parents[2]

PROBE = """
import json, os
import psutil
from rocas.search.ray_executor import RayExecutor

ex = RayExecutor(1)
try:
    squares = ex.map(lambda batch: [x * x for x in batch], [[1, 2], [3]])
    me = psutil.Process()
    listen = []
    for p in [me] + me.children(recursive=True):
        try:
            conns = p.net_connections(kind="inet")
        except (psutil.NoSuchProcess, psutil.AccessDenied):
            continue
        listen += [[p.name(), c.laddr.ip, c.laddr.port] for c in conns
                   if c.status == psutil.CONN_LISTEN]
    print(json.dumps({"node": ex.node_address, "listen": listen, "squares": squares,
                      "auth": os.environ.get("RAY_AUTH_MODE")}))
finally:
    ex.close()
"""


def _loopback(ip: str) -> bool:
    addr = ipaddress.ip_address(ip)
    mapped = getattr(addr, "ipv4_mapped", None)
    return (mapped or addr).is_loopback


def test_a_private_ray_listens_on_loopback_only_and_demands_its_token():
    ray = pytest.importorskip("ray")
    pytest.importorskip("psutil")
    env = {k: v for k, v in os.environ.items() if k not in ("RAY_ADDRESS", "RAY_AUTH_MODE")}
    env["PYTHONPATH"] = os.pathsep.join([str(ROOT), env.get("PYTHONPATH", "")])
    res = subprocess.run([sys.executable, "-c", PROBE], cwd=ROOT, env=env, capture_output=True,
                         text=True, timeout=300)
    if res.returncode != 0 and "cannot start or join a local Ray" in res.stderr:
        pytest.skip(f"this machine cannot run a local Ray: {res.stderr.strip().splitlines()[-1]}")
    assert res.returncode == 0, res.stderr
    found = json.loads(res.stdout.strip().splitlines()[-1])
    assert found["squares"] == [[1, 4], [9]]
    assert found["node"] == "127.0.0.1"
    names = {name for name, _, _ in found["listen"]}
    assert {"gcs_server", "raylet"} <= names, found["listen"]
    assert [s for s in found["listen"] if not _loopback(s[1])] == []
    if ray_version(ray) >= ray_executor.TOKEN_AUTH_SINCE:
        assert found["auth"] == "token"


def test_the_private_environment_asks_for_loopback_and_the_token(monkeypatch):
    monkeypatch.delenv("RAY_AUTH_MODE", raising=False)
    assert private_ray_environment(types.SimpleNamespace(__version__="2.60.0")) == {
        "RAY_ENABLE_WINDOWS_OR_OSX_CLUSTER": "0", "RAY_AUTH_MODE": "token"}
    # a Ray without token authentication: loopback only
    assert private_ray_environment(types.SimpleNamespace(__version__="2.51.1")) == {
        "RAY_ENABLE_WINDOWS_OR_OSX_CLUSTER": "0"}
    # a mode the user chose is theirs
    monkeypatch.setenv("RAY_AUTH_MODE", "disabled")
    assert "RAY_AUTH_MODE" not in private_ray_environment(types.SimpleNamespace(__version__="2.60.0"))


def test_ray_version_reads_release_and_development_versions():
    assert ray_version(types.SimpleNamespace(__version__="2.60.0")) == (2, 60, 0)
    assert ray_version(types.SimpleNamespace(__version__="3.0.0.dev0")) == (3, 0, 0)
    assert ray_version(types.SimpleNamespace(__version__="2.52rc1")) == (2, 52)
    assert ray_version(types.SimpleNamespace()) == (0,)


def test_the_environment_is_restored_after_the_start(monkeypatch):
    monkeypatch.delenv("RAY_ENABLE_WINDOWS_OR_OSX_CLUSTER", raising=False)
    monkeypatch.delenv("RAY_AUTH_MODE", raising=False)
    constants = types.SimpleNamespace(ENABLE_RAY_CLUSTER=True)
    refreshed = []
    fake = types.SimpleNamespace(__version__="2.60.0",
                                 _private=types.SimpleNamespace(ray_constants=constants),
                                 _raylet=types.SimpleNamespace(Config=types.SimpleNamespace(
                                     initialize=lambda s: refreshed.append(s))))
    with ray_executor._private_ray_environment(fake):
        assert constants.ENABLE_RAY_CLUSTER is False
        assert os.environ["RAY_ENABLE_WINDOWS_OR_OSX_CLUSTER"] == "0"
        assert os.environ["RAY_AUTH_MODE"] == "token" and refreshed == [""]
    assert constants.ENABLE_RAY_CLUSTER is True
    assert "RAY_ENABLE_WINDOWS_OR_OSX_CLUSTER" not in os.environ
