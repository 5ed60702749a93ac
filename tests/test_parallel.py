"""kinematics.parallel: the launch lock hands iterations out in chunks, restores numba's per-thread
setting, and the chunking changes no result."""

from __future__ import annotations

import threading

import numba
import numpy as np
import pytest

from paraspace.kinematics import parallel
from paraspace.kinematics.design import Design
from paraspace.kinematics.orientation import OrientationSettings, orientation_workspace
from paraspace.kinematics.parallel import KERNEL_LOCK, kernel_launch
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
