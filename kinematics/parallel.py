"""One lock for every launch of a ``parallel=True`` numba kernel, and how a launch shares its work.

numba's ``workqueue`` threading layer (the one used when neither OpenMP's ``libgomp`` nor TBB is
installed, e.g. in a slim container) aborts the whole process when two Python threads launch
parallel kernels at once -- and the explorer and the REST API run jobs on several threads. Each
launch already uses every core, so holding this lock for the (short, chunked) launches costs no
throughput and makes the core safe under any threading layer.

Waiting policy: numba's ``omp`` layer (libgomp) lets idle worker threads spin between launches by
default. On a loaded machine a spinning thread takes the core from the thread that has work, and
two threads end up slower than one (measured: 0.45 s vs 0.31 s for the h = 2 workspace with a
second process busy on one core). Unless the user chose a policy, the threads sleep instead
(``OMP_WAIT_POLICY=PASSIVE``; set here, before libgomp is loaded at the first parallel launch),
which costs a few microseconds per launch on an idle machine.

Sharing policy: by default numba splits a ``prange`` into one equal slice per thread. Holding
:data:`KERNEL_LOCK` also sets numba's ``parallel_chunksize`` (a per-thread setting restored on
release) to :data:`DEFAULT_CHUNK` iterations, and :func:`kernel_launch` sizes the chunks from the
launch's iteration count. The results do not depend on the chunking or the thread count: each
iteration writes only its own outputs.

Static slices: the chunks are handed out dynamically (a thread that finishes one takes the next)
only by the ``tbb`` layer. The ``omp`` layer (the one this project gets from the wheels: libgomp's
``omp for`` is statically scheduled) and the ``workqueue`` layer give each thread an equal
contiguous slice of the chunks, so with any chunk size a launch whose costly iterations sit together
waits for the thread that got them (measured, 2 threads: 64 iterations whose first 32 hold all the
work take 95 ms with chunks of 0, 1 or 4 under ``omp`` and ``workqueue``, 51 ms with chunks of 1
under ``tbb``, 48 ms with the work interleaved; ``tests/test_parallel.py`` checks the slices). A
launch over items of known unequal cost therefore orders them with
:func:`kinematics.slices.dealt_order` (:func:`dealt_launch`), and one over items of unknown cost that
sit together in space visits them strided (:func:`kinematics.slices.strided`): both balance the
slices under every layer. (Until issue 24's last round this paragraph said the chunks balanced the
threads under ``omp``; they never did.)

Busy machine: Linux schedules each login session as one group (``sched_autogroup``) and shares the
CPU fairly between the groups, so when the other sessions already keep every core busy a second
thread adds no CPU time to ours, only wake-ups and the barrier at the end of every launch
(measured on the shared 2-core machine at load average 6-7 from other sessions: 2 threads 0.70x
the speed of 1 for the blocks and dense engines and the orientation scan, chunks or not). Each
launch therefore counts the other runnable tasks (``/proc/loadavg``'s instantaneous count) and
uses one thread when they are at least as many as the cores (:func:`launch_threads`; same
measurement: 0.96x, 0.77x, 0.76x -- the count is a snapshot of bursty work and misses some of
it). With one other busy process on a 2-core machine both threads stay (under ``omp`` each keeps its
slice, "Static slices" below, so the thread that shares its core finishes last).
``LOAD_RULE = False`` turns the rule off; without ``/proc/loadavg`` every thread is used.

Background launches (:meth:`_KernelLock.background`): the warm-up compiles every kernel on first
call, inside the lock, for minutes on a cold cache; a plain lock is not fair (the thread that
releases it takes it back before a waiting thread wakes), so a job started meanwhile waited for the
whole warm-up (measured on a fresh install, 2 cores: the explorer's first display shell waited
147 s for the lock, its first measures another 90 s). A thread inside ``background()`` takes the
lock only while no other thread waits for it: a waiting job gets it as soon as the launch (or
compile) in progress ends.

Thread count set after import (:func:`adopt_thread_env`): numba reads ``NUMBA_NUM_THREADS`` when
it is imported and again before each compilation, and refuses a change once its threads are
running. A Dask worker gets its environment (one thread: ``kinematics.distributed.WORKER_ENV``)
after the spawned process has re-imported the parent's main module -- which imports numba when the
parent is ``paraspace`` itself -- so its threads would start at the machine's core count, every
launch would use them all, and its first compilation (a kernel missing from numba's cache) would
fail. The worker's warm-up adopts the environment's count first.
"""

from __future__ import annotations

import contextlib
import os
import threading
import time
from collections.abc import Iterator
from typing import Any

import numpy as np

os.environ.setdefault("OMP_WAIT_POLICY", "PASSIVE")

#: Iterations per chunk of a launch made while holding :data:`KERNEL_LOCK`.
DEFAULT_CHUNK = 8
#: Chunks per thread of a :func:`kernel_launch`.
CHUNKS_PER_THREAD = 8
#: Use one thread when the other runnable tasks fill every core (module docstring, "Busy machine").
LOAD_RULE = True

_CORES = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else (os.cpu_count() or 1)


def _other_runnable() -> int | None:
    """Runnable tasks on the machine other than the calling thread (``/proc/loadavg``'s 4th field
    counts the running and runnable tasks, the caller included); ``None`` where unavailable."""
    try:
        with open("/proc/loadavg", "rb") as fh:
            running = int(fh.read().split()[3].split(b"/")[0])
    except (OSError, ValueError, IndexError):
        return None
    return max(0, running - 1)


def launch_threads(configured: int) -> int:
    """Threads for the next launch: ``configured``, or 1 when at least as many other tasks are
    runnable as there are cores (module docstring, "Busy machine"); ``configured`` when
    :data:`LOAD_RULE` is off or the count is unavailable."""
    if not LOAD_RULE or configured <= 1:
        return configured
    others = _other_runnable()
    if others is None or others < _CORES:
        return configured
    return 1


#: Most threads one launch may use in this process (``None``: numba's count), set from the
#: environment by :func:`adopt_thread_env` and applied by :data:`KERNEL_LOCK` in every thread.
_THREAD_CAP: int | None = None


def adopt_thread_env() -> int:
    """Make this process's launches use the ``NUMBA_NUM_THREADS`` of the environment as it is now
    (module docstring, "Thread count set after import"); returns the threads a launch will use.

    numba fixes the threads it starts when it is imported, so the count is applied as a cap on every
    launch under :data:`KERNEL_LOCK` (``numba.set_num_threads`` is per Python thread). Its
    configuration is reloaded from the environment before its threads start; after, the
    environment is set back to the count they started with, so that no later compilation fails."""
    global _THREAD_CAP
    import numba
    from numba.core import config

    raw = os.environ.get("NUMBA_NUM_THREADS", "").strip()
    wanted = int(raw) if raw.isdigit() and int(raw) >= 1 else None
    try:
        config.reload_config()
    except RuntimeError:  # the threads run with the count numba read at import
        os.environ["NUMBA_NUM_THREADS"] = str(int(config.NUMBA_NUM_THREADS))
    _THREAD_CAP = wanted
    n = numba.get_num_threads()
    return n if wanted is None else min(n, wanted)


def _set_chunk(n: int) -> int:
    import numba

    return int(numba.set_parallel_chunksize(int(n)))


class _KernelLock:
    """A :class:`threading.Lock` whose ``with`` block launches with :data:`DEFAULT_CHUNK`-sized
    chunks and :func:`launch_threads` threads in the holding thread (module docstring); both are
    per-thread numba settings, restored on release. A thread inside :meth:`background` yields the
    lock to every thread waiting for it (module docstring, *Background launches*)."""

    def __init__(self) -> None:
        self._lock = threading.Lock()
        self._previous = 0
        self._threads = 1
        self._waiting = 0  # foreground threads waiting for the lock
        self._turn = threading.Condition(threading.Lock())
        self._local = threading.local()

    @contextlib.contextmanager
    def background(self) -> Iterator[None]:
        """The current thread's launches in the block wait while another thread waits for the lock."""
        before = getattr(self._local, "background", False)
        self._local.background = True
        try:
            yield
        finally:
            self._local.background = before

    def acquire(self, blocking: bool = True, timeout: float = -1) -> bool:
        """As :meth:`threading.Lock.acquire`; a background thread first waits while another thread
        waits for the lock (``blocking=False``: returns False at once then; ``timeout``: waits at most
        that long in all)."""
        if getattr(self._local, "background", False):
            deadline = time.monotonic() + timeout if blocking and timeout >= 0 else None
            with self._turn:
                while self._waiting:
                    if not blocking:
                        return False
                    left = None if deadline is None else deadline - time.monotonic()
                    if left is not None and left <= 0:
                        return False
                    self._turn.wait(left)
            if deadline is None:
                return self._lock.acquire(blocking)
            return self._lock.acquire(True, max(deadline - time.monotonic(), 0.0))
        with self._turn:
            self._waiting += 1
        try:
            return self._lock.acquire(blocking, timeout)
        finally:
            with self._turn:
                self._waiting -= 1
                if not self._waiting:
                    self._turn.notify_all()

    def release(self) -> None:
        self._lock.release()

    def locked(self) -> bool:
        return self._lock.locked()

    def __enter__(self) -> _KernelLock:
        import numba

        self.acquire()
        try:
            self._previous = _set_chunk(DEFAULT_CHUNK)
            self._threads = numba.get_num_threads()
            n = launch_threads(self._threads)
            if _THREAD_CAP is not None:
                n = min(n, _THREAD_CAP)
            if n != self._threads:
                numba.set_num_threads(n)
        except BaseException:
            self._lock.release()
            raise
        return self

    def __exit__(self, *exc: Any) -> None:
        import numba

        try:
            _set_chunk(self._previous)
            if numba.get_num_threads() != self._threads:
                numba.set_num_threads(self._threads)
        finally:
            self._lock.release()


KERNEL_LOCK = _KernelLock()


@contextlib.contextmanager
def dealt_launch(costs: np.ndarray) -> Iterator[np.ndarray]:
    """Hold :data:`KERNEL_LOCK` for one launch over items of estimated ``costs``, yielding the order
    to launch them in (:func:`kinematics.slices.dealt_order` for the launch's thread count; the
    kernel skips ``-1``), with numba's even split into one slice per thread."""
    import numba

    from .slices import dealt_order  # imported here: kinematics.slices imports numba, as the lines above do

    with KERNEL_LOCK:
        order = dealt_order(costs, numba.get_num_threads())
        previous = _set_chunk(0)
        try:
            yield order
        finally:
            _set_chunk(previous)


@contextlib.contextmanager
def kernel_launch(n_items: int) -> Iterator[None]:
    """Hold :data:`KERNEL_LOCK` for one launch of a ``parallel=True`` kernel over ``n_items``
    iterations of unequal cost, handed out in chunks of about ``n_items / (CHUNKS_PER_THREAD
    threads)`` iterations (at least 1)."""
    import numba

    with KERNEL_LOCK:
        previous = _set_chunk(max(1, -(-int(n_items) // (CHUNKS_PER_THREAD * max(1, numba.get_num_threads())))))
        try:
            yield
        finally:
            _set_chunk(previous)
