"""The server's memory is returned after shell downloads (trust item 8): a real server process builds the same
shell file N times (its shell-file cache made too small to hold it, so every download rebuilds it:
the worst case), and its RSS, read from /proc, comes back within 10 % of the level before."""

from __future__ import annotations

import os
import subprocess
import sys
import time

import httpx
import pytest

from paraspace.app.serve import free_port

pytestmark = pytest.mark.skipif(not os.path.exists("/proc/self/status"), reason="needs /proc (Linux)")

SERVER = ("from paraspace.app.serve import serve; from paraspace.app.api import ApiLimits; "
          "serve('127.0.0.1', 0, {port}, explorer=False, quiet=True, limits=ApiLimits(shell_cache_bytes=1000))")


def _rss_mb(pid: int) -> float:
    with open(f"/proc/{pid}/status") as fh:
        for line in fh:
            if line.startswith("VmRSS:"):
                return int(line.split()[1]) / 1024.0
    raise AssertionError("no VmRSS in /proc status")


@pytest.mark.slow
def test_rss_returns_after_repeated_shell_downloads() -> None:
    port = free_port()
    proc = subprocess.Popen([sys.executable, "-c", SERVER.format(port=port)])
    base = f"http://127.0.0.1:{port}/api/v1"
    try:
        with httpx.Client(timeout=300) as c:  # guards against a hung server, not a speed limit
            deadline = time.monotonic() + 900
            while True:
                assert proc.poll() is None, "the server process exited"
                assert time.monotonic() < deadline, "the server did not warm up within 900 s"
                try:
                    if c.get(f"{base}/health").json().get("warm"):
                        break
                except httpx.HTTPError:
                    pass
                time.sleep(0.5)
            job = c.post(f"{base}/workspace", json={"settings": {"voxel": 3}}).json()["job_id"]
            deadline = time.monotonic() + 900
            while (st := c.get(f"{base}/jobs/{job}").json()["status"]) not in ("done", "failed", "cancelled"):
                assert time.monotonic() < deadline, "the workspace job did not finish within 900 s"
                time.sleep(0.2)
            assert st == "done"
            first = c.get(f"{base}/workspace/{job}/shell.stl")  # first build: imports, code pages
            assert first.status_code == 200 and len(first.content) > 100_000
            before = _rss_mb(proc.pid)
            for _ in range(20):
                r = c.get(f"{base}/workspace/{job}/shell.stl")
                assert r.status_code == 200 and r.content == first.content
            after = _rss_mb(proc.pid)
        grown = 20 * len(first.content) / 2**20
        print(f"RSS before {before:.0f} MB, after 20 rebuilds of a {len(first.content) / 2**20:.1f} MB shell: "
              f"{after:.0f} MB")
        assert after <= 1.10 * before, (before, after, f"{grown:.0f} MB of shell files were built")
    finally:
        proc.terminate()
        proc.wait(60)
