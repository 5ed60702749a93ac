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

Sharing policy: by default numba splits a ``prange`` into one equal slice per thread, so when one
core is busy with another process the thread on it holds the whole launch back (2 threads were
measured slower than 1 under load). Holding :data:`KERNEL_LOCK` therefore also hands the
iterations out in chunks (numba's ``parallel_chunksize``, a per-thread setting restored on
release): a thread that finishes a chunk takes the next one, so the thread on the free core does
most of the work and 2 threads are not slower than 1. :data:`DEFAULT_CHUNK` iterations per chunk
(every kernel's iteration costs at least one feasibility test, so the per-chunk cost of a fraction
of a microsecond is negligible); :func:`kernel_launch` sizes the chunks from the launch's iteration count. The
results do not depend on the chunking: each iteration writes only its own outputs.
"""

from __future__ import annotations

import contextlib
import os
import threading
from typing import Any, Iterator

os.environ.setdefault("OMP_WAIT_POLICY", "PASSIVE")

#: Iterations per chunk of a launch made while holding :data:`KERNEL_LOCK`.
DEFAULT_CHUNK = 8
#: Chunks per thread of a :func:`kernel_launch`.
CHUNKS_PER_THREAD = 8


def _set_chunk(n: int) -> int:
    import numba

    return int(numba.set_parallel_chunksize(int(n)))


class _KernelLock:
    """A :class:`threading.Lock` whose ``with`` block launches with :data:`DEFAULT_CHUNK`-sized
    chunks in the holding thread (module docstring, "Sharing policy"; a per-thread numba setting,
    restored on release)."""

    def __init__(self) -> None:
        self._lock = threading.Lock()
        self._previous = 0

    def acquire(self, blocking: bool = True, timeout: float = -1) -> bool:
        return self._lock.acquire(blocking, timeout)

    def release(self) -> None:
        self._lock.release()

    def locked(self) -> bool:
        return self._lock.locked()

    def __enter__(self) -> "_KernelLock":
        self._lock.acquire()
        try:
            self._previous = _set_chunk(DEFAULT_CHUNK)
        except BaseException:
            self._lock.release()
            raise
        return self

    def __exit__(self, *exc: Any) -> None:
        try:
            _set_chunk(self._previous)
        finally:
            self._lock.release()


KERNEL_LOCK = _KernelLock()


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
