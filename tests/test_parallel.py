"""kinematics.parallel: the launch lock hands iterations out in chunks, restores numba's per-thread
setting, and the chunking changes no result."""

from __future__ import annotations

import threading
import time
from typing import Any

import numba
import numpy as np
import pytest

from paraspace.kinematics import parallel
from paraspace.kinematics.design import Design
from paraspace.kinematics.orientation import OrientationSettings, orientation_workspace
from paraspace.kinematics.parallel import KERNEL_LOCK, dealt_launch, kernel_launch
from paraspace.kinematics.workspace import WorkspaceSettings, compute_workspace


def test_lock_sets_and_restores_the_chunk_size() -> None:
    before = numba.get_parallel_chunksize()
    with KERNEL_LOCK:
        assert KERNEL_LOCK.locked()
        assert numba.get_parallel_chunksize() == parallel.DEFAULT_CHUNK
        assert not KERNEL_LOCK.acquire(blocking=False)  # still a mutual exclusion
    assert not KERNEL_LOCK.locked()
    assert numba.get_parallel_chunksize() == before
    with pytest.raises(RuntimeError):
        with KERNEL_LOCK:
            raise RuntimeError("boom")
    assert not KERNEL_LOCK.locked() and numba.get_parallel_chunksize() == before


def test_kernel_launch_chunks_follow_the_size(monkeypatch) -> None:
    monkeypatch.setattr(parallel, "LOAD_RULE", False)  # the thread count the chunks are sized for
    threads = numba.get_num_threads()
    per = parallel.CHUNKS_PER_THREAD * threads
    for n, want in ((1, 1), (per, 1), (per + 1, 2), (100 * per, 100)):
        with kernel_launch(n):
            assert numba.get_parallel_chunksize() == want
            assert KERNEL_LOCK.locked()
    assert not KERNEL_LOCK.locked() and numba.get_parallel_chunksize() == 0


@numba.njit(parallel=True)
def _thread_of(out):
    for t in numba.prange(out.shape[0]):
        out[t] = numba.get_thread_id()


def test_a_dealt_launch_runs_one_slice_per_thread(monkeypatch: pytest.MonkeyPatch) -> None:
    """The layout :func:`kinematics.slices.dealt_order` is made for: with the ``omp`` or ``workqueue`` layer a launch's
    iterations run in equal contiguous slices, one per thread, however the chunks are set (so the
    chunks do not balance unequal iterations there; module docstring, "Static slices")."""
    # both launches on every thread: the busy-machine rule would run either on one when the other
    # worker of the suite keeps the cores busy (seen in CI: one thread, then two)
    monkeypatch.setattr(parallel, "LOAD_RULE", False)
    if numba.config.NUMBA_NUM_THREADS < 2:
        pytest.skip("one thread")
    _thread_of(np.zeros(1, np.int64))
    if numba.threading_layer() == "tbb":
        pytest.skip("TBB hands the chunks out dynamically")
    costs = np.arange(13.0)
    with dealt_launch(costs) as order:
        threads = numba.get_num_threads()
        seen = np.zeros(order.size, np.int64)
        _thread_of(seen)
    q = order.size // threads
    assert order.size == threads * q
    for t in range(threads):
        assert np.unique(seen[t * q:(t + 1) * q]).size == 1
    assert np.unique(seen).size == threads
    with KERNEL_LOCK:  # chunks of one: still contiguous slices
        numba.set_parallel_chunksize(1)
        chunked = np.zeros(order.size, np.int64)
        _thread_of(chunked)
    for t in range(threads):
        assert np.unique(chunked[t * q:(t + 1) * q]).size == 1


def test_chunk_size_is_per_thread() -> None:
    seen: list[int] = []
    with KERNEL_LOCK:
        t = threading.Thread(target=lambda: seen.append(numba.get_parallel_chunksize()))
        t.start()
        t.join()
    assert seen == [0]


@pytest.mark.parametrize("method", ["blocks", "dense"])
def test_chunking_and_threads_change_no_voxel(method: str, monkeypatch) -> None:
    st = WorkspaceSettings(voxel=5.0, method=method, diagnostics=True)
    ref = compute_workspace(Design(), st)
    assert 1000 < ref.occupancy.sum() < ref.occupancy.size
    for chunk in (0, 1, 3):
        monkeypatch.setattr(parallel, "DEFAULT_CHUNK", chunk)
        for threads in (1, numba.config.NUMBA_NUM_THREADS):
            numba.set_num_threads(threads)
            try:
                res = compute_workspace(Design(), st)
            finally:
                numba.set_num_threads(numba.config.NUMBA_NUM_THREADS)
            assert np.array_equal(res.chain_mask, ref.chain_mask), (chunk, threads)


def test_orientation_scan_independent_of_threads() -> None:
    s = OrientationSettings(angle_range=60.0, angle_step=3.0, position_step=4.0)
    ref = orientation_workspace(Design(), s)
    numba.set_num_threads(1)
    try:
        one = orientation_workspace(Design(), s)
    finally:
        numba.set_num_threads(numba.config.NUMBA_NUM_THREADS)
    for key, reg in ref.regions.items():
        assert np.array_equal(reg.feasible, one.regions[key].feasible), key
    assert (ref.ti1, ref.ti2) == (one.ti1, one.ti2)


def test_one_thread_when_other_tasks_fill_the_cores(monkeypatch) -> None:
    cores = parallel._CORES
    for others, want in ((0, 4), (cores - 1, 4), (cores, 1), (cores + 5, 1), (None, 4)):
        monkeypatch.setattr(parallel, "_other_runnable", lambda o=others: o)
        assert parallel.launch_threads(4) == want, others
    monkeypatch.setattr(parallel, "LOAD_RULE", False)
    assert parallel.launch_threads(4) == 4
    monkeypatch.setattr(parallel, "LOAD_RULE", True)
    assert parallel.launch_threads(1) == 1


def test_lock_lowers_and_restores_the_thread_count(monkeypatch) -> None:
    if numba.config.NUMBA_NUM_THREADS < 2:
        pytest.skip("one thread only")
    monkeypatch.setattr(parallel, "_other_runnable", lambda: parallel._CORES)
    numba.set_num_threads(2)
    with KERNEL_LOCK:
        assert numba.get_num_threads() == 1
    assert numba.get_num_threads() == 2
    monkeypatch.setattr(parallel, "_other_runnable", lambda: 0)
    with KERNEL_LOCK:
        assert numba.get_num_threads() == 2


def test_other_runnable_reads_the_kernel_count() -> None:
    n = parallel._other_runnable()
    assert n is None or n >= 0


_ADOPT = r"""
import os, sys
import numba, numpy as np
from numba import njit, prange

def compiled():  # a kernel that is not in numba's cache: its compilation reloads numba's configuration
    @njit(parallel=True)
    def total(a):
        s = 0.0
        for i in prange(a.shape[0]):
            s += a[i]
        return s
    return total

launched_first = sys.argv[1] == "launched"
if launched_first:  # numba's threads already run when the environment arrives
    compiled()(np.ones(8))
os.environ["NUMBA_NUM_THREADS"] = "1"  # as a Dask nanny sets a worker's environment, after numba's import
from paraspace.kinematics.parallel import KERNEL_LOCK, adopt_thread_env
print(adopt_thread_env())
f = compiled()
with KERNEL_LOCK:
    print(numba.get_num_threads(), f(np.ones(8)))
print(compiled()(np.ones(3)))
"""


@pytest.mark.parametrize("when", ["before", "launched"])
def test_a_thread_count_set_after_numbas_import_is_adopted(when, tmp_path) -> None:
    """A Dask worker's environment (NUMBA_NUM_THREADS=1, kinematics.distributed.WORKER_ENV) arrives
    after numba was imported; its warm-up's adopt_thread_env makes every launch under the kernel lock
    use one thread and keeps later compilations from failing (numba refuses a thread count that
    differs from the running threads'), whether numba's threads had started or not."""
    import os
    import subprocess
    import sys

    if (os.cpu_count() or 1) < 2:
        pytest.skip("needs a default thread count other than 1")
    script = tmp_path / "adopt.py"
    script.write_text(_ADOPT)
    env = {k: v for k, v in os.environ.items() if k != "NUMBA_NUM_THREADS"}
    proc = subprocess.run([sys.executable, str(script), when], capture_output=True, text=True, timeout=300, env=env)
    assert proc.returncode == 0, proc.stderr[-2000:]
    assert proc.stdout.split() == ["1", "1", "8.0", "3.0"]


def test_a_waiting_thread_goes_before_a_background_thread_that_takes_the_lock_back() -> None:
    """The warm-up takes the kernel lock for one launch (or compile) after another; a job waiting for
    it must get it when the launch in progress ends, not when the warm-up is over. A plain lock is
    taken back by the thread that releases it (a fresh install's first shell waited 147 s)."""
    lock = parallel._KernelLock()
    started = threading.Event()
    stop = threading.Event()
    holds: list[float] = []

    def warm_up_like() -> None:
        with lock.background():
            while not stop.is_set() and len(holds) < 300:  # at most about 6 s
                with lock:
                    started.set()
                    t = time.perf_counter()
                    while time.perf_counter() - t < 0.02:  # a compile: 20 ms holding the GIL
                        pass
                holds.append(time.monotonic())

    bg = threading.Thread(target=warm_up_like)
    bg.start()
    try:
        assert started.wait(10.0)
        time.sleep(0.1)
        t0 = time.monotonic()
        with lock:
            waited = time.monotonic() - t0
            during = sum(t >= t0 for t in holds)
        # a plain lock: 0.5-3.9 s and 24-195 launches meanwhile (2026-11-29, 2 cores); this one: 1
        assert waited < 2.0 and during <= 5, f"waited {waited:.2f} s, {during} background launches meanwhile"
        n = len(holds)
        time.sleep(0.2)
        assert len(holds) > n  # nobody waits: the background thread goes on
    finally:
        stop.set()
        bg.join(10.0)
    assert not bg.is_alive()
    assert not getattr(lock._local, "background", False)  # this thread was never a background one


def test_a_background_thread_that_may_not_wait_does_not_wait() -> None:
    """``acquire(blocking=False)`` (or with a timeout) in a background thread answers at once (or by
    its timeout) while a foreground thread waits for the lock, and takes the lock when nobody waits:
    the yielding of :meth:`_KernelLock.background` never makes a non-blocking call block."""
    lock = parallel._KernelLock()
    holder_in, release = threading.Event(), threading.Event()
    results: dict = {}

    def holder() -> None:
        with lock:
            holder_in.set()
            release.wait(10.0)

    def background(key: str, **kw: Any) -> None:
        with lock.background():
            t = time.monotonic()
            got = lock.acquire(**kw)
            results[key] = (got, time.monotonic() - t)
            if got:
                lock.release()

    background("free", blocking=False)  # nobody holds it, nobody waits: taken
    assert results["free"][0]
    h = threading.Thread(target=holder)
    h.start()
    assert holder_in.wait(10.0)
    waiter = threading.Thread(target=lambda: (lock.acquire(), lock.release()))
    waiter.start()  # a foreground thread waiting for the lock
    deadline = time.monotonic() + 10.0
    while not lock._waiting and time.monotonic() < deadline:
        time.sleep(0.01)
    assert lock._waiting == 1
    background("now", blocking=False)
    background("timeout", timeout=0.3)
    assert results["now"][0] is False and results["now"][1] < 0.2
    assert results["timeout"][0] is False and 0.25 <= results["timeout"][1] < 2.0
    release.set()
    h.join(10.0)
    waiter.join(10.0)
    assert not lock.locked()
