"""Regression tests for the reliability and abuse defects found under fuzzing and load (issues 12
and 13). Every loop is bounded in count and time and talks only to 127.0.0.1."""

from __future__ import annotations

import errno
import json
import logging
import socket
import threading
import time
import urllib.parse

import httpx
import numpy as np
import pytest

from paraspace.app import cli
from paraspace.app.api import API_PREFIX, ApiLimits, create_api, decode_link_token
from paraspace.app.jobs import JobManager
from paraspace.app.serve import check_public_url, serve, start_api
from paraspace.kinematics.bytecache import ByteLRU, nbytes
from paraspace.kinematics.design import ParameterError

V1 = API_PREFIX


@pytest.fixture
def api():
    """A fresh API (own job manager) on a free loopback port; yields (url, jobs)."""
    jobs = JobManager(max_workers=2, max_jobs_total=16, max_jobs_per_client=8, max_seconds=60)
    srv = start_api(create_api(jobs, explorer_url="http://127.0.0.1:9999/",
                               limits=ApiLimits(max_jobs_per_client=2, max_voxels=3_000_000, max_body_seconds=1.0)),
                    "127.0.0.1", 0, header_timeout=1.0)
    yield srv.url, jobs
    jobs.shutdown(wait=False)
    srv.stop()


# ----- issue 12 -----------------------------------------------------------------------------------

def test_forwarded_for_does_not_make_new_clients(api):
    """12.1: one connection sending many X-Forwarded-For addresses is still one client."""
    url, jobs = api
    codes = []
    with httpx.Client(base_url=url, timeout=30) as c:
        for i in range(4):
            r = c.post(f"{V1}/workspace", json={"settings": {"voxel": 3.0 + 0.1 * i, "eta_step": 0.02, "method": "dense"}},
                       headers={"X-Forwarded-For": f"10.0.0.{i + 1}"})
            codes.append(r.status_code)
            if r.status_code == 202:
                assert r.json()["job"]["client"] == "api:127.0.0.1"
    assert codes[:2] == [202, 202] and codes[2:] == [429, 429], codes
    for j in jobs.active():
        jobs.cancel(j.id)


def test_a_small_job_does_not_wait_behind_another_clients_heavy_jobs():
    """12.2: client A fills the queue with slow jobs; client B's tiny job runs while A's still run."""
    jobs = JobManager(max_workers=2, max_jobs_per_client=8)
    release = threading.Event()
    try:
        heavy = [jobs.submit(lambda p, c: release.wait(30), kind="w", client="A") for _ in range(4)]
        time.sleep(0.2)
        small = jobs.submit(lambda p, c: 42, kind="w", client="B")
        assert small.wait(10), "B's job did not run while A's jobs were running"
        assert small.result == 42
        assert sum(j.status == "running" for j in heavy) == 1  # A holds at most max_workers - 1 workers
        assert all(not j.is_final for j in heavy)
    finally:
        release.set()
        jobs.shutdown(wait=True)


def test_fair_pick_prefers_the_client_with_fewer_running_jobs():
    jobs = JobManager(max_workers=3, max_jobs_per_client=8, max_running_per_client=3)
    release = threading.Event()
    order: list[str] = []
    try:
        for _ in range(3):
            jobs.submit(lambda p, c: release.wait(30), kind="w", client="A")
        time.sleep(0.2)  # A runs 3 (the cap allows it), nothing queued
        queued = [jobs.submit(lambda p, c, n=n: order.append(n), kind="w", client=n[0]) for n in ("A1", "A2", "B1")]
        release.set()
        for j in queued:
            assert j.wait(10)
        assert order.index("B1") < order.index("A2")
    finally:
        release.set()
        jobs.shutdown(wait=True)


def test_history_and_caches_are_bounded_by_bytes():
    """12.3 / 13.4: finished jobs keep results within history_bytes; older ones keep a summary."""
    jobs = JobManager(max_workers=1, history_bytes=30 << 20, max_jobs_per_client=64, max_jobs_total=64)
    try:
        done = [jobs.submit(lambda p, c: np.ones(10 << 20, dtype=np.uint8), kind="g", client="x",
                            summarize=lambda r: {"n": int(r.size)}) for _ in range(8)]
        for j in done:
            assert j.wait(20)
        time.sleep(0.1)
        held = sum(nbytes(j.result) for j in done)
        assert held <= 30 << 20
        assert isinstance(done[-1].result, np.ndarray)  # the newest result is kept whole
        assert done[0].result == {"n": 10 << 20}  # the oldest keeps its summary
        assert jobs.stats()["history_result_bytes"] <= 30 << 20
    finally:
        jobs.shutdown(wait=True)
    lru = ByteLRU(1000)
    assert lru.put("a", b"x" * 600) and lru.put("b", b"y" * 300)
    assert lru.put("c", b"z" * 300) and "a" not in lru and lru.total_bytes <= 1000
    assert not lru.put("huge", b"w" * 2000) and "huge" not in lru


def test_the_one_cache_bounds_entries_as_well_as_bytes():
    """The explorer's Optimize runs and every other cache are one ByteLRU: least recently used out
    first, by count when ``max_entries`` is given, by bytes always."""
    lru = ByteLRU(10_000, size=len, max_entries=3)
    for k in "abcde":
        assert lru.put(k, b"x" * 100)
    assert len(lru) == 3 and "a" not in lru and "b" not in lru and lru.total_bytes == 300
    assert lru.get("c") == b"x" * 100  # c is now the most recently used: d is the oldest
    lru.put("f", b"y")
    assert "d" not in lru and "c" in lru and lru.total_bytes == 201
    assert not ByteLRU(1000, max_entries=0).put("k", b"v")
    with pytest.raises(ValueError, match="max_entries"):
        ByteLRU(1000, max_entries=-1)


def test_slow_headers_and_bodies_are_cut_off(api):
    """12.4: a connection that never finishes its request head is closed; a dripped body gets 408
    (both limits 1 s here)."""
    url, _ = api
    host, port = urllib.parse.urlsplit(url).netloc.split(":")
    s = socket.create_connection((host, int(port)), timeout=5)
    s.sendall(b"GET /api/v1/health HTTP/1.1\r\nHost: 127.0.0.1\r\n")  # no blank line: the head never ends
    s.settimeout(5)
    t0 = time.monotonic()
    assert s.recv(1024) == b""  # closed by the server (header_timeout = 1 s here)
    assert time.monotonic() - t0 < 4.9
    s.close()
    s = socket.create_connection((host, int(port)), timeout=20)
    s.sendall(b"POST /api/v1/ik HTTP/1.1\r\nHost: 127.0.0.1\r\nContent-Type: application/json\r\n"
              b"Content-Length: 100\r\n\r\n{")
    s.settimeout(20)
    reply = s.recv(4096)
    while b"}" not in reply and (more := s.recv(4096)):  # the head and the body may come apart
        reply += more
    assert reply.startswith(b"HTTP/1.1 408"), reply[:80]
    assert b"max_body_seconds" in reply
    s.close()


def test_numbers_are_strict(api):
    """12.5: true or "60" is not a length."""
    url, _ = api
    with httpx.Client(base_url=url, timeout=30) as c:
        for bad in (True, "60", None):
            r = c.post(f"{V1}/ik", json={"design": {"a": bad}})
            assert r.status_code == 422 and r.json()["detail"][0]["field"] == "design.a"
        assert c.post(f"{V1}/ik", json={"design": {"a": 60}}).status_code == 200
        r = c.post(f"{V1}/ik", json={"pose": {"x": 0, "y": 0, "z": 130, "psi": 0, "theta": 0, "phi": 0},
                                    "d": [1, 2, True], "eta": [0, 0, 0]})
        assert r.status_code == 422


@pytest.mark.slow
def test_a_lost_cluster_ends_the_sweep_with_the_points_done(monkeypatch, capsys):
    """12.8 / 13.7: every worker gone -> the sweep returns within a bounded time, the missing points
    are reported failed, and the CLI exits non-zero saying how many."""
    from distributed import LocalCluster

    from paraspace.kinematics.design import Design
    from paraspace.kinematics.distributed import sweep_grid
    from paraspace.kinematics.workspace import WorkspaceSettings

    cluster = LocalCluster(n_workers=1, threads_per_worker=1, processes=False, dashboard_address=None)
    try:
        addr = cluster.scheduler_address
        killer = threading.Timer(2.0, lambda: cluster.scale(0))
        killer.start()

        def slow_eval(design, settings, *, orientation=None):
            time.sleep(0.5)
            return {"volume": float(design.a)}

        t0 = time.monotonic()
        rows = sweep_grid(Design(), {"a": [float(v) for v in range(20, 80, 2)]}, WorkspaceSettings(voxel=8),
                          scheduler=addr, evaluate=slow_eval, lost_after=2.0)
        elapsed = time.monotonic() - t0
        killer.join()
        ok = [r for r in rows if r["ok"]]
        lost = [r for r in rows if not r["ok"]]
        assert len(rows) == 30 and lost and ok
        assert all("cluster lost" in r["error"] for r in lost), [r["error"] for r in lost]
        assert elapsed < 60
    finally:
        cluster.close()
    # the CLI's exit status for such a result
    monkeypatch.setattr("paraspace.kinematics.sweep.sweep_1d",
                        lambda *a, **k: [{"value": 1.0, "volume": 1.0, "ok": True},
                                         {"value": 2.0, "ok": False, "error": "cluster lost: no worker"}])
    code = cli.main(["sweep", "--param", "a", "--values", "20,30", "--voxel", "8"])
    assert code == 1
    assert "1 of 2 points failed" in capsys.readouterr().err


@pytest.mark.slow
def test_a_result_lost_with_the_last_worker_is_reported_as_the_lost_cluster(monkeypatch):
    """The CI of 2026-12-04 (second run): a point had finished, and its result went with the last
    worker before the sweep fetched it; its row said "TimeoutError: timed out after 2 s." instead of
    the lost cluster. Here the cluster is scaled to 0 just before the fourth result is fetched."""
    import distributed
    from distributed import LocalCluster

    from paraspace.kinematics.design import Design
    from paraspace.kinematics.distributed import sweep_grid
    from paraspace.kinematics.workspace import WorkspaceSettings

    def quick_eval(design, settings, *, orientation=None):
        time.sleep(0.2)
        return {"volume": float(design.a)}

    cluster = LocalCluster(n_workers=1, threads_per_worker=1, processes=False, dashboard_address=None)
    real, fetched = distributed.Future.result, []

    def result(self, timeout=None):
        if len(fetched) == 3:  # the last worker leaves with this point's result
            cluster.scale(0)
            t0 = time.monotonic()
            while cluster.workers and time.monotonic() - t0 < 10:
                time.sleep(0.05)
            time.sleep(0.5)
        fetched.append(self.status)
        return real(self, timeout=timeout)

    monkeypatch.setattr(distributed.Future, "result", result)
    try:
        rows = sweep_grid(Design(), {"a": [float(v) for v in range(20, 80, 2)]}, WorkspaceSettings(voxel=8),
                          scheduler=cluster.scheduler_address, evaluate=quick_eval, lost_after=2.0)
    finally:
        cluster.close()
    assert fetched[:3] == ["finished"] * 3 and len(fetched) == 4
    ok = [r for r in rows if r["ok"]]
    lost = [r for r in rows if not r["ok"]]
    assert len(rows) == 30 and len(ok) == 3 and len(lost) == 27
    assert all(r["volume"] == r["params"]["a"] for r in ok)
    assert all(r["error"].startswith("cluster lost: no worker") for r in lost), [r["error"] for r in lost]
    went = [r for r in lost if "this point: finished, but its result did not come within 2 s" in r["error"]]
    assert len(went) == 1


# ----- issue 13 -----------------------------------------------------------------------------------

def test_sweep_points_obey_the_grid_limit(api):
    """13.3: a one-point sweep at a tiny voxel is refused like the workspace itself."""
    url, _ = api
    with httpx.Client(base_url=url, timeout=60) as c:
        r = c.post(f"{V1}/sweep", json={"x": {"param": "a", "values": [50]}, "settings": {"voxel": 0.55}})
        assert r.status_code == 413
        assert "sweep point 0" in r.json()["detail"] and "max_voxels = 3000000" in r.json()["detail"]


def test_quota_is_checked_before_any_estimate(api, monkeypatch):
    """13.5: once a client is at its job limit, further requests are refused without computing the
    grid estimate (which is what kept hundreds of requests running)."""
    url, jobs = api
    calls = []
    import paraspace.app.limits as limits_mod

    real = limits_mod.workspace_voxels
    monkeypatch.setattr(limits_mod, "workspace_voxels", lambda *a, **k: (calls.append(1), real(*a, **k))[1])
    with httpx.Client(base_url=url, timeout=30) as c:
        for i in range(2):
            assert c.post(f"{V1}/workspace", json={"settings": {"voxel": 3.0 + 0.1 * i, "eta_step": 0.02, "method": "dense"}}).status_code == 202
        n = len(calls)
        for i in range(5):
            assert c.post(f"{V1}/workspace", json={"settings": {"voxel": 4.0 + 0.1 * i}}).status_code == 429
        assert len(calls) == n
        assert c.post(f"{V1}/ik", json={}).status_code == 200
    for j in jobs.active():
        jobs.cancel(j.id)


def test_a_full_disk_is_a_clear_message(api, monkeypatch):
    """13.6: ENOSPC inside a job ends it failed with a sentence; the server keeps answering."""
    url, _ = api

    def full(*a, **k):
        raise OSError(errno.ENOSPC, "No space left on device")

    monkeypatch.setattr("paraspace.kinematics.workspace.compute_workspace", full)
    with httpx.Client(base_url=url, timeout=30) as c:
        r = c.post(f"{V1}/workspace", params={"wait": 10}, json={"settings": {"voxel": 9.5}})
        job = r.json()["job"]
        assert job["status"] == "failed" and "disk is full" in job["error"]
        assert c.get(f"{V1}/health").status_code == 200
        assert c.post(f"{V1}/ik", json={}).status_code == 200


def test_unreadable_bodies_name_the_body(api):
    """13.9: deep JSON and invalid UTF-8 get 422 naming the field 'body'."""
    url, _ = api
    with httpx.Client(base_url=url, timeout=30) as c:
        for content in (b"[" * 100_000 + b"]" * 100_000, b'{"design": {"a": "\xff"}}', b'{"design": '):
            r = c.post(f"{V1}/ik", content=content, headers={"content-type": "application/json"})
            assert r.status_code in (413, 422), r.status_code
            if r.status_code == 422:
                assert r.json()["detail"][0]["field"] == "body"


@pytest.mark.parametrize("token", ["z!!!!", "q%%", "zAAAA", "q" + "A" * 5, "x123"])
def test_garbage_tokens_are_404(api, token):
    """13.10"""
    url, _ = api
    with pytest.raises(ValueError):
        decode_link_token(token)
    with httpx.Client(base_url=url, timeout=30, follow_redirects=False) as c:
        assert c.get(f"/s/{urllib.parse.quote(token)}").status_code == 404


def test_links_never_reflect_the_host_header(api):
    """13.11: redirects and links come from the configured URL, whatever Host the request says (a
    host that is not allowed gets no answer at all: app/hostcheck.py)."""
    url, _ = api
    with httpx.Client(base_url=url, timeout=30, follow_redirects=False) as c:
        assert c.get("/s?a=60", headers={"Host": "evil.example"}).status_code == 403
        r = c.get("/s?a=60", headers={"Host": "localhost"})
        assert r.status_code == 307 and r.headers["location"].startswith("http://127.0.0.1:9999/")
        tok = c.post(f"{V1}/links", json={"query": "a=60"}, headers={"Host": "localhost"}).json()
        assert "localhost" not in (tok["explorer_url"] or "")
    assert check_public_url("https://robots.example.org/paraspace") == "https://robots.example.org/paraspace/"
    for bad in ("javascript:alert(1)", "ftp://x", "http://", "https://x/?a=1"):
        with pytest.raises(ParameterError):
            check_public_url(bad)


def test_startup_says_there_is_no_authentication(capsys):
    running = serve("127.0.0.1", 0, 0, block=False, explorer=False)
    try:
        assert "no authentication" in capsys.readouterr().out
    finally:
        running.stop()


def test_cli_file_errors_are_one_line(tmp_path, capsys):
    """13.12: an unwritable --export path is one line and exit 2, no traceback."""
    code = cli.main(["workspace", "--voxel", "10", "--export", str(tmp_path / "missing" / "x.stl")])
    err = capsys.readouterr().err
    assert code == 2 and err.startswith("paraspace: error: cannot use the file") and "Traceback" not in err


def test_progress_goes_to_a_terminal_only(capsys):
    import io

    from paraspace.app.progressline import progress_line

    p, close = progress_line("x", io.StringIO())
    assert p is None
    buf = io.StringIO()
    p, close = progress_line("x", buf, force=True)
    p(0.5, "half")
    close()
    assert "50 %" in buf.getvalue() and "half" in buf.getvalue()
    code = cli.main(["workspace", "--voxel", "12", "--json"])
    out = capsys.readouterr()
    assert code == 0 and json.loads(out.out)["volume"] > 0 and "%" not in out.err


def test_a_long_progress_message_is_cut_between_words():
    """The bar's message is cut to at most 60 characters at a space, marked with "...": the engine's
    "(level 1 of 5: 432 blocks tested, ...)" was drawn as "... 432 blocks test" (a cut word reads as
    another word); a short message is drawn whole."""
    import io

    from paraspace.app.progressline import MESSAGE_CHARS, progress_line

    msg = "computing the workspace, 20 % (level 1 of 5: 432 blocks tested, 1,648 smaller ones near the boundary next)"
    buf = io.StringIO()
    p, close = progress_line("workspace", buf, force=True)
    p(0.2, msg)
    close()
    drawn = buf.getvalue()
    assert "computing the workspace, 20 % (level 1 of 5: 432 blocks..." in drawn and "blocks test" not in drawn
    shown = drawn[drawn.index("computing"):].split("...")[0] + "..."
    assert len(shown) <= MESSAGE_CHARS and msg.startswith(shown[:-3])
    buf = io.StringIO()
    p, close = progress_line("x", buf, force=True)
    p(0.5, "level 2 of 5")
    close()
    assert "level 2 of 5" in buf.getvalue() and "..." not in buf.getvalue()


def test_oversized_explorer_links_get_an_answer_and_no_traceback(caplog):
    from paraspace.app.explorer import Explorer

    exp = Explorer("127.0.0.1", 0).start()
    try:
        host, port = urllib.parse.urlsplit(exp.url).netloc.split(":")

        def raw_get(n: int) -> bytes:
            with socket.create_connection((host, int(port)), timeout=20) as s:
                s.sendall(b"GET /?a=" + b"9" * n + b" HTTP/1.1\r\nHost: 127.0.0.1\r\n\r\n")
                chunks = []
                while True:
                    try:
                        data = s.recv(65536)
                    except OSError:
                        break
                    if not data:
                        break
                    chunks.append(data)
                    if b"\r\n\r\n" in b"".join(chunks) and len(b"".join(chunks)) > 200:
                        break
                return b"".join(chunks)

        with caplog.at_level(logging.DEBUG):
            reply = raw_get(100_000)  # a 100 KB share link
            assert reply.startswith(b"HTTP/1.1 414") and b"limited to" in reply
            assert raw_get(400_000) == b""  # beyond the request-line limit: dropped, quietly
            time.sleep(0.5)
        assert not any(rec.exc_info for rec in caplog.records), [r.getMessage() for r in caplog.records]
    finally:
        exp.stop()
