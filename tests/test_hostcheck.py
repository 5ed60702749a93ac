"""Host and origin rules (app/hostcheck.py) over real sockets: a rebinding domain or a foreign web
page can neither drive the explorer's websocket nor use the REST API; the server's own pages and
plain local clients still can."""

from __future__ import annotations

import asyncio
import http.client
from collections.abc import Iterator

import httpx
import pytest
import viser
import websockets.asyncio.client
import websockets.exceptions
import websockets.typing

from paraspace.app.api import API_PREFIX, create_api
from paraspace.app.explorer import Explorer
from paraspace.app.hostcheck import HostPolicy, host_name, parse_allowed_hosts
from paraspace.app.jobs import JobManager
from paraspace.app.serve import ApiServer, start_api


def test_policy_rules() -> None:
    p = HostPolicy.for_server("127.0.0.1", explorer_port=8080)
    assert p.refusal("127.0.0.1:8081", None) is None
    assert p.refusal("localhost:8081", "http://localhost:8081") is None  # own origin
    assert p.refusal("127.0.0.1:8081", "http://127.0.0.1:8080") is None  # the explorer's page
    assert p.refusal("[::1]:8081", None) is None
    assert "Host 'attacker.example:8081' is not allowed" in p.refusal("attacker.example:8081", None)
    assert p.refusal("LOCALHOST.:8081", None) is None  # case and trailing dot do not matter
    for origin in ("http://evil.example", "null", "http://127.0.0.1:9999", "file://", "http://localhost:8080.evil"):
        assert "is not allowed" in p.refusal("127.0.0.1:8081", origin), origin
    assert p.refusal(None, None) is not None  # HTTP/1.0 without Host: refused
    public = HostPolicy.for_server("0.0.0.0", explorer_port=8080, public_url="https://robots.example.org/ps/")
    assert public.refusal("robots.example.org", "https://robots.example.org") is None
    assert public.refusal("0.0.0.0:8080", None) is not None  # a wildcard bind is no host name
    extra = HostPolicy.for_server("127.0.0.1", allowed_hosts=parse_allowed_hosts("lab-pc, Lab-PC.local"))
    assert extra.refusal("lab-pc.local:8080", None) is None and extra.refusal("other:8080", None) is not None
    anyhost = HostPolicy.for_server("0.0.0.0", allowed_hosts=parse_allowed_hosts("*"))
    assert anyhost.refusal("whatever.example", None) is None
    assert anyhost.refusal("whatever.example", "http://evil.example") is not None  # origins still checked
    assert host_name("[::1]:80") == "::1" and host_name("Example.ORG:1") == "example.org"


@pytest.fixture(scope="module")
def api() -> Iterator[ApiServer]:
    jobs = JobManager(max_workers=1)
    srv = start_api(create_api(jobs, hosts=HostPolicy.for_server("127.0.0.1", explorer_port=8080)), "127.0.0.1", 0)
    yield srv
    jobs.shutdown(wait=False)
    srv.stop()


def test_api_refuses_a_rebinding_host_before_any_work(api: ApiServer) -> None:
    with httpx.Client(base_url=api.url, timeout=30) as http:
        r = http.post(f"{API_PREFIX}/workspace", json={"settings": {"voxel": 8}},
                      headers={"Host": "attacker.example"})
        assert r.status_code == 403
        assert "Host 'attacker.example' is not allowed" in r.json()["detail"]
        counts = http.get(f"{API_PREFIX}/health").json()["jobs"]["counts"]
        assert sum(counts.values()) == 0, f"the refused request made a job: {counts}"
        r = http.get(f"{API_PREFIX}/health", headers={"Origin": "http://evil.example"})
        assert r.status_code == 403 and "Origin 'http://evil.example'" in r.json()["detail"]
        assert http.get(f"{API_PREFIX}/health").status_code == 200
        assert http.get(f"{API_PREFIX}/health", headers={"Host": "localhost"}).status_code == 200
        assert http.get(f"{API_PREFIX}/health", headers={"Origin": "http://127.0.0.1:8080"}).status_code == 200


@pytest.fixture(scope="module")
def explorer() -> Iterator[Explorer]:
    exp = Explorer("127.0.0.1", 0).start()
    yield exp
    exp.stop()


def _handshake(port: int, origin: str | None) -> int:
    async def go() -> int:
        headers = {"Origin": origin} if origin is not None else None
        try:
            async with websockets.asyncio.client.connect(
                    f"ws://127.0.0.1:{port}", additional_headers=headers, open_timeout=30,
                    subprotocols=[websockets.typing.Subprotocol(f"viser-v{viser.__version__}")]):
                return 101
        except websockets.exceptions.InvalidStatus as e:
            return e.response.status_code
    return asyncio.run(go())


def test_explorer_websocket_refuses_foreign_origins(explorer: Explorer) -> None:
    port = explorer.port
    assert _handshake(port, "http://evil.example") == 403
    assert _handshake(port, "null") == 403
    assert _handshake(port, f"http://127.0.0.1:{port + 1}") == 403
    assert _handshake(port, f"http://127.0.0.1:{port}") == 101
    assert _handshake(port, f"http://localhost:{port}") == 101  # the same server under another loopback name
    assert _handshake(port, f"http://localhost:{port + 1}") == 403  # another local web app
    assert _handshake(port, None) == 101  # a local program, not a page


def test_explorer_page_refuses_a_rebinding_host(explorer: Explorer) -> None:
    conn = http.client.HTTPConnection("127.0.0.1", explorer.port, timeout=30)
    conn.request("GET", "/", headers={"Host": f"attacker.example:{explorer.port}"})
    r = conn.getresponse()
    body = r.read().decode()
    assert r.status == 403 and "not allowed" in body and r.getheader("Content-Type").startswith("text/plain")
    conn = http.client.HTTPConnection("127.0.0.1", explorer.port, timeout=30)
    conn.request("GET", "/")
    assert conn.getresponse().status == 200
