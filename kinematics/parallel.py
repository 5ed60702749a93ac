"""One lock for every launch of a ``parallel=True`` numba kernel.

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
"""

from __future__ import annotations

import contextlib
import os
import threading
from typing import Iterator

os.environ.setdefault("OMP_WAIT_POLICY", "PASSIVE")

KERNEL_LOCK = threading.Lock()


#: Chunks per thread of a launch (dynamic scheduling, :func:`kernel_launch`).
CHUNKS_PER_THREAD = 8


@contextlib.contextmanager
def kernel_launch(n_items: int) -> Iterator[None]:
    """Hold :data:`KERNEL_LOCK` for one launch of a ``parallel=True`` kernel over ``n_items``
    iterations, handed to the threads in chunks of about ``n_items / (CHUNKS_PER_THREAD threads)``
    (numba's ``parallel_chunksize``: a thread that finishes a chunk takes the next one). With the
    default equal split a thread sharing its core with another process holds the whole launch
    back; with chunks the other thread takes over the rest of the work."""
    import numba

    chunk = max(1, -(-int(n_items) // (CHUNKS_PER_THREAD * max(1, numba.get_num_threads()))))
    with KERNEL_LOCK:
        previous = numba.set_parallel_chunksize(chunk)
        try:
            yield
        finally:
            numba.set_parallel_chunksize(previous)
