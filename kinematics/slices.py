r"""How a launch's iterations reach the threads, and two orders that give each thread an equal share.

**Static slices.** numba's ``omp`` layer (libgomp's ``omp for``, statically scheduled) and its
``workqueue`` layer run a ``prange`` of ``N`` iterations on ``T`` threads as ``T`` contiguous slices:
thread ``t`` runs the iterations ``[t q, (t + 1) q)``, ``q = ceil(N / T)``, whatever numba's
``parallel_chunksize`` (the chunks are dealt out the same way; only the ``tbb`` layer hands them out
dynamically). A launch is as slow as its most loaded slice, so iterations whose cost sits together
(the planes at the edge of a workspace, the undecided blocks along its boundary) leave one thread
working while the others wait. Measured on 2 threads: 64 iterations whose first 32 hold all the
work take 95 ms in grid order (chunks of 0, 1 or 4), 48 ms interleaved. ``tests/test_parallel.py``
checks the slices with ``numba.get_thread_id``.

**Dealt order** (items of known cost ``c_k``): sorted by cost, largest first, and dealt to the slices
back and forth, ``0, 1, ..., T-1, T-1, ..., 0, 0, 1, ...``; each slice is padded with ``-1`` (no item)
to the same length ``q``. Two slices' totals then differ by at most ``max_k c_k`` (each pair of
rounds gives every slice one item of each half of the pair, so the differences telescope).

**Strided order** (items of unknown cost): position ``p`` of the launch visits item
``(p mod q) T + floor(p / q)`` (none when that is ``>= N``), so slice ``t`` visits the items
``t, t + T, t + 2T, ...``: every slice samples the whole range evenly.

Neither order changes a result: each iteration writes only its own outputs.
"""

from __future__ import annotations

import numpy as np
from numba import njit


def dealt_order(costs: np.ndarray, threads: int) -> np.ndarray:
    """The order in which to launch items of estimated ``costs`` so that ``threads`` equal contiguous
    slices of it (how numba's ``omp`` and ``workqueue`` layers hand a launch out, module docstring,
    "Static slices") carry nearly equal costs: the items by cost, largest first, dealt to the slices
    back and forth (``0 .. T-1``, then ``T-1 .. 0``, ...), each slice padded with ``-1`` (no item) to
    the same length. Returns int64 indices into ``costs`` and ``-1`` pads, ``T * ceil(n / T)`` of
    them."""
    c = np.asarray(costs, float).ravel()
    t = max(1, int(threads))
    if c.size == 0:
        return np.zeros(0, np.int64)
    q = -(-c.size // t)
    rank = np.argsort(-c, kind="stable")
    rounds, pos = np.divmod(np.arange(c.size), t)
    slot = np.where(rounds % 2 == 0, pos, t - 1 - pos)
    out = np.full((t, q), -1, np.int64)
    out[slot, rounds] = rank
    return out.ravel()


@njit(cache=True, forceinline=True)
def strided(pos: int, per: int, threads: int) -> int:
    """The item visited at position ``pos`` of a launch of ``threads * per`` positions in the strided
    order (module docstring); ``>= N`` for a position past the last item (the caller skips it)."""
    return (pos % per) * threads + pos // per
