"""One client cannot starve the others (trust item 7): connections over real sockets, and the job
queue across kinds (tests/test_jobs.py)."""

from __future__ import annotations

import socket

from paraspace.app.api import API_PREFIX, create_api
from paraspace.app.jobs import JobManager
from paraspace.app.serve import start_api


def _raw_get(base_port: int, path: str, source: str = "127.0.0.1") -> int:
    """Status of ``GET path`` over a new connection from ``source`` (a loopback address)."""
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as s:
        s.settimeout(60)
        s.bind((source, 0))
        s.connect(("127.0.0.1", base_port))
        s.sendall(f"GET {path} HTTP/1.1\r\nHost: 127.0.0.1:{base_port}\r\nConnection: close\r\n\r\n".encode())
        data = b""
        while b"\r\n" not in data:
            chunk = s.recv(4096)
            if not chunk:
                break
            data += chunk
    return int(data.split(b" ", 2)[1]) if data.startswith(b"HTTP/1.1 ") else 0


def test_one_client_holding_many_idle_connections_starves_nobody() -> None:
    """Client A (127.0.0.1) opens more connections than the whole server allows and sends nothing;
    /health from another address (127.0.0.2) and a new request from A's own address still answer
    200, and A never holds more than its per-client share."""
    from paraspace.app.serve import MAX_CONNECTIONS, MAX_CONNECTIONS_PER_CLIENT

    jobs = JobManager(max_workers=1)
    srv = start_api(create_api(jobs), "127.0.0.1", 0)
    held: list[socket.socket] = []
    try:
        for _ in range(MAX_CONNECTIONS + 50):
            held.append(socket.create_connection(("127.0.0.1", srv.port), timeout=60))
        assert _raw_get(srv.port, f"{API_PREFIX}/health", "127.0.0.2") == 200
        assert _raw_get(srv.port, f"{API_PREFIX}/health") == 200
        assert _raw_get(srv.port, f"{API_PREFIX}/design/defaults", "127.0.0.3") == 200
        open_ = 0
        for s in held:  # closed by the server: recv returns b"" at once; open: times out
            s.settimeout(0.05)
            try:
                open_ += s.recv(1) != b""
            except TimeoutError:
                open_ += 1
        assert open_ <= MAX_CONNECTIONS_PER_CLIENT, open_
    finally:
        for s in held:
            s.close()
        srv.stop()
        jobs.shutdown(wait=False)
