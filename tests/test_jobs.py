"""JobManager: ordering under supersede, limits, crashes, time limit, cancellation (all fast)."""

from __future__ import annotations

import threading
import time

import pytest

from paraspace.app.jobs import FINAL_STATUSES, Job, JobManager, LimitExceeded
from paraspace.kinematics.progress import Cancelled


def _until(block: threading.Event):
    """A job that runs until ``block`` is set (returning 1), or raises Cancelled once cancelled."""
    def fn(progress, cancel):
        while not block.is_set():
            if cancel.is_set():
                raise Cancelled()
            time.sleep(0.005)
        return 1
    return fn


def _sleeper(seconds: float, result="ok"):
    """A cooperative job: sleeps in small steps, reporting progress and honouring cancel."""
    def fn(progress, cancel):
        n = max(1, int(seconds / 0.005))
        for i in range(n):
            if cancel.is_set():
                raise Cancelled()
            time.sleep(0.005)
            progress((i + 1) / n, f"step {i + 1}/{n}")
        return result
    return fn


@pytest.fixture
def jm():
    m = JobManager(max_workers=2, max_jobs_total=16, max_jobs_per_client=4, max_seconds=30.0)
    yield m
    m.shutdown(wait=True)


def test_job_runs_and_reports(jm):
    seen = []
    job = jm.submit(_sleeper(0.05, result=42), kind="t", on_done=seen.append)
    assert isinstance(job, Job)
    assert job.wait(10)
    assert job.status == "done" and job.result == 42 and job.progress == 1.0 and job.error is None
    assert seen == [job]
    d = job.to_dict()
    assert "result" not in d and d["status"] == "done" and d["id"] == job.id
    assert jm.get(job.id) is job
    assert job.started is not None and job.finished >= job.started >= job.created


def test_supersede_ordering_last_wins(jm):
    """20 superseding submissions in a burst: only the last ends done, the rest cancelled."""
    done_results = []
    lock = threading.Lock()

    def on_done(job):
        with lock:
            done_results.append((job.id, job.status, job.result))

    jobs = []
    t0 = time.perf_counter()
    for i in range(20):
        jobs.append(jm.submit(_sleeper(0.05, result=i), kind="slider", client="c1",
                              supersede=True, on_done=on_done))
    print(f"20 superseding submissions took {1e3 * (time.perf_counter() - t0):.2f} ms")
    for j in jobs:
        assert j.wait(10)
    assert [j.status for j in jobs[:-1]] == ["cancelled"] * 19
    assert jobs[-1].status == "done" and jobs[-1].result == 19
    assert all(j.result is None for j in jobs[:-1])
    # on_done was called once per job; only the last reports "done"
    assert len(done_results) == 20
    assert [r for r in done_results if r[1] == "done"] == [(jobs[-1].id, "done", 19)]


def test_supersede_is_per_client_and_kind(jm):
    a = jm.submit(_sleeper(0.2), kind="k", client="A")
    b = jm.submit(_sleeper(0.05), kind="k", client="B", supersede=True)
    c = jm.submit(_sleeper(0.05), kind="other", client="A", supersede=True)
    for j in (a, b, c):
        assert j.wait(10)
    assert (a.status, b.status, c.status) == ("done", "done", "done")


def test_result_arriving_after_supersede_is_dropped(jm):
    """A job that ignores the token and returns anyway cannot end done once superseded."""
    started = threading.Event()
    release = threading.Event()

    def stubborn(progress, cancel):
        started.set()
        release.wait(5)
        return "late"

    first = jm.submit(stubborn, kind="k", client="c", supersede=True)
    assert started.wait(5)
    second = jm.submit(_sleeper(0.01, "new"), kind="k", client="c", supersede=True)
    release.set()
    assert first.wait(5) and second.wait(5)
    assert first.status == "cancelled" and first.result is None
    assert second.status == "done" and second.result == "new"


def test_dedupe_by_key(jm):
    calls = []

    def fn(progress, cancel):
        calls.append(1)
        time.sleep(0.1)
        return "v"

    j1 = jm.submit(fn, kind="ws", client="c", key=("x", 1))
    j2 = jm.submit(fn, kind="ws", client="c", key=("x", 1))
    assert j1 is j2
    assert j1.wait(5) and j1.result == "v" and len(calls) == 1


def test_limit_per_client_and_total():
    m = JobManager(max_workers=1, max_jobs_total=3, max_jobs_per_client=2, max_seconds=30.0)
    try:
        block = threading.Event()
        fn = _until(block)
        j = [m.submit(fn, kind="k", client="A"), m.submit(fn, kind="k", client="A")]
        with pytest.raises(LimitExceeded) as e:
            m.submit(fn, kind="k", client="A")
        assert "max_jobs_per_client" in str(e.value) and "2" in str(e.value)
        assert e.value.limit == "max_jobs_per_client" and e.value.value == 2
        j.append(m.submit(fn, kind="k", client="B"))
        with pytest.raises(LimitExceeded) as e:
            m.submit(fn, kind="k", client="C")
        assert "max_jobs_total" in str(e.value) and "3" in str(e.value)
        # cancelling frees the slot immediately: B's job may be queued or already running on the
        # reserve worker (A holds the only normal one), and either way C may submit at once
        assert m.cancel(j[2].id)
        j.append(m.submit(fn, kind="k", client="C"))
        assert j[2].wait(5) and j[2].status == "cancelled"
        block.set()
        for x in j:
            assert x.wait(5)
        assert [x.status for x in j] == ["done", "done", "cancelled", "done"]
        assert m.active() == []
    finally:
        m.shutdown(wait=True)


def test_crash_marks_failed_and_worker_survives(jm):
    def boom(progress, cancel):
        raise ZeroDivisionError("bad\nthing   happened")

    j = jm.submit(boom, kind="k")
    assert j.wait(5)
    assert j.status == "failed"
    assert j.error == "ZeroDivisionError: bad thing happened"  # one line
    ok = jm.submit(_sleeper(0.01, "fine"), kind="k")
    assert ok.wait(5) and ok.status == "done" and ok.result == "fine"


def test_time_limit_cooperative():
    m = JobManager(max_workers=1, max_seconds=0.2)
    try:
        t0 = time.perf_counter()
        j = m.submit(_sleeper(20.0), kind="k")
        assert j.wait(10)
        print(f"time-limited job reported after {time.perf_counter() - t0:.3f} s (limit 0.2 s)")
        assert j.status == "failed"
        assert j.error == "time limit of 0.2 s exceeded"
        assert j.cancel_token.is_set()
        # the worker is free again
        nxt = m.submit(_sleeper(0.01, "next"), kind="k")
        assert nxt.wait(5) and nxt.status == "done"
    finally:
        m.shutdown(wait=True)


def test_time_limit_per_job_and_non_cooperative():
    m = JobManager(max_workers=2, max_seconds=10.0)
    try:
        release = threading.Event()

        def deaf(progress, cancel):
            release.wait(5)  # ignores the token
            return "late"

        j = m.submit(deaf, kind="k", max_seconds=0.1)
        assert j.wait(5)  # reported failed at the limit, before fn returns
        assert j.status == "failed" and "time limit of 0.1 s" in j.error
        release.set()
        time.sleep(0.05)
        assert j.status == "failed" and j.result is None
    finally:
        m.shutdown(wait=True)


def test_cancel_mid_job(jm):
    j = jm.submit(_sleeper(5.0), kind="k")
    while j.progress == 0.0:
        time.sleep(0.005)
    assert j.status == "running"
    t0 = time.perf_counter()
    j.cancel()
    assert j.wait(5)
    print(f"cancel latency {1e3 * (time.perf_counter() - t0):.1f} ms")
    assert j.status == "cancelled" and 0 < j.progress < 1
    # the final status takes the message; the last step the work reported stays to say where it was
    assert not j.message.startswith("step ") and j.progress_message.startswith("step ")
    assert j.elapsed is not None and 0 < j.elapsed < 10 and j.to_dict()["elapsed_seconds"] == round(j.elapsed, 6)
    assert not jm.cancel(j.id)  # already final
    assert not jm.cancel("nope")


def test_progress_raises_cancelled_after_cancel(jm):
    """A job that only reports progress is still cancellable through the progress callable."""
    def only_progress(progress, cancel):
        for i in range(10_000):
            time.sleep(0.002)
            progress(i / 10_000, "x")
        return 1

    j = jm.submit(only_progress, kind="k")
    time.sleep(0.05)
    jm.cancel(j.id)
    assert j.wait(5) and j.status == "cancelled"


def test_get_unknown_and_history_bounded():
    m = JobManager(max_workers=1, history=5)
    try:
        with pytest.raises(KeyError):
            m.get("missing")
        jobs = [m.submit(lambda p, c, i=i: i, kind="k") for i in range(3)]
        for j in jobs:
            j.wait(5)
        more = []
        for i in range(8):
            x = m.submit(lambda p, c, i=i: i, kind="k")
            x.wait(5)
            more.append(x)
        assert len(m.jobs()) == 5
        with pytest.raises(KeyError):
            m.get(jobs[0].id)
        assert m.get(more[-1].id).result == 7
    finally:
        m.shutdown(wait=True)


def test_shutdown_cancels_and_refuses():
    m = JobManager(max_workers=1)
    a = m.submit(_sleeper(5.0), kind="k")
    b = m.submit(_sleeper(5.0), kind="k")
    m.shutdown(wait=True)
    assert a.status in FINAL_STATUSES and a.status == "cancelled"
    assert b.status == "cancelled"
    with pytest.raises(RuntimeError):
        m.submit(_sleeper(0.01), kind="k")


def test_on_done_exception_does_not_break(jm):
    def bad_cb(job):
        raise RuntimeError("callback bug")

    j = jm.submit(_sleeper(0.01, 3), kind="k", on_done=bad_cb)
    assert j.wait(5) and j.status == "done"
    j2 = jm.submit(_sleeper(0.01, 4), kind="k")
    assert j2.wait(5) and j2.result == 4


def test_real_workspace_job_cancel_and_progress(jm):
    """The core's compute_workspace runs as a job; progress moves and cancel stops it."""
    from paraspace.kinematics.design import Design
    from paraspace.kinematics.workspace import WorkspaceSettings, compute_workspace

    s = WorkspaceSettings(voxel=10.0)
    ok = jm.submit(lambda p, c: compute_workspace(Design(), s, p, c), kind="ws")
    assert ok.wait(120), ok.to_dict()
    assert ok.status == "done" and ok.result.volume > 0
    fine = WorkspaceSettings(voxel=0.5)
    j = jm.submit(lambda p, c: compute_workspace(Design(), fine, p, c), kind="ws")
    time.sleep(0.3)
    j.cancel()
    assert j.wait(30)
    assert j.status == "cancelled", j.to_dict()


def test_job_overhead_printed(jm):
    """Submit-to-done latency of trivial jobs (printed, not asserted)."""
    t0 = time.perf_counter()
    lat = []
    for i in range(200):
        t = time.perf_counter()
        j = jm.submit(lambda p, c, i=i: i, kind="trivial")
        assert j.wait(5) and j.result == i
        lat.append(time.perf_counter() - t)
    lat.sort()
    print(f"trivial job submit->done: median {1e6 * lat[100]:.0f} us, p95 {1e6 * lat[190]:.0f} us, "
          f"{200 / (time.perf_counter() - t0):.0f} jobs/s sequential")


def test_another_clients_job_starts_whatever_kinds_one_client_runs():
    """Client A keeps both workers busy with two jobs of different kinds (an optimisation and a
    workspace): client B's small job still runs to completion while A's jobs are still running."""
    m = JobManager(max_workers=2, max_jobs_total=16, max_jobs_per_client=4, max_seconds=120.0)
    release = threading.Event()
    started = threading.Semaphore(0)

    def heavy(progress, cancel):
        started.release()
        release.wait(120)
        return "heavy"

    try:
        a1 = m.submit(heavy, kind="optimize", client="A")
        a2 = m.submit(heavy, kind="workspace", client="A")
        for _ in range(2):
            assert started.acquire(timeout=60), "client A's jobs did not both start within 60 s"
        assert a1.status == a2.status == "running"
        b = m.submit(lambda progress, cancel: "small", kind="workspace", client="B")
        assert b.wait(60), "client B's job did not finish within 60 s while A's jobs ran"
        assert b.status == "done" and b.result == "small"
        assert a1.status == a2.status == "running"
        # the reserve serves only a client with nothing running: A's third job waits for A's others
        a3 = m.submit(lambda progress, cancel: "a3", kind="sweep", client="A")
        assert not a3.wait(0.3) and a3.status == "queued"
    finally:
        release.set()
        m.shutdown(wait=True)


def test_a_session_holds_a_job_of_every_kind_and_every_pin_at_once():
    """The explorer's sessions run one job per kind (each superseding its last) and one per pin; the
    session's own limit lets all of them be unfinished at once even where the manager's per-client
    limit for REST clients is 2, so the jobs that follow a result (orientation maps, the bracket)
    are never refused because of the pins. A kind outside the list, or one that does not
    supersede, is refused by name."""
    from paraspace.app.explorer.session import SESSION_JOB_KINDS, SESSION_JOB_LIMIT, SessionJobs
    from paraspace.app.urlstate import MAX_PINS

    m = JobManager(max_workers=1, max_jobs_total=64, max_jobs_per_client=2)
    block = threading.Event()
    fn = _until(block)
    try:
        sj = SessionJobs(m, lambda: False)
        jobs = [sj.submit(fn, kind="pin", client="viser-1") for _ in range(MAX_PINS)]
        jobs += [sj.submit(fn, kind=k, client="viser-1", supersede=True) for k in sorted(SESSION_JOB_KINDS)]
        assert len(jobs) == SESSION_JOB_LIMIT
        assert len(m.active("viser-1")) == SESSION_JOB_LIMIT
        # one more is refused with the session's limit in the message
        with pytest.raises(LimitExceeded, match=f"max_jobs_per_client = {SESSION_JOB_LIMIT}"):
            sj.submit(fn, kind="pin", client="viser-1")
        # a REST client keeps the manager's limit
        m.submit(fn, kind="k", client="rest")
        m.submit(fn, kind="k", client="rest")
        with pytest.raises(LimitExceeded, match="max_jobs_per_client = 2"):
            m.submit(fn, kind="k", client="rest")
        with pytest.raises(ValueError, match="'novel'"):
            sj.submit(fn, kind="novel", client="viser-1", supersede=True)
        with pytest.raises(ValueError, match="supersede"):
            sj.submit(fn, kind="task", client="viser-1")
        block.set()
        assert all(j.wait(5) for j in jobs)
    finally:
        block.set()
        m.shutdown(wait=True)
