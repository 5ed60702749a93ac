r"""Voids of a voxel set by a flood from where the complement leaks, not by labelling it.

Definition (that of :mod:`kinematics.voids`): pad the grid with one unreachable layer; the
complement ``C = pad(G) \ W``, split into components with the dual adjacency (26 neighbours for a
6-connected ``W``, 6 for a 26-connected one), has one component holding the padding, the outside
``O``; the voids are ``C \ O``.

Computation. An unreachable voxel with no reachable voxel on one side along some axis is joined to
the padding by that straight line (a path for 6 and for 26 neighbours), so it lies in ``O``. The
others are the *candidates* ``K`` (``voids._enclosed_ext_kernel``). A path from a candidate to the
padding leaves ``K`` at a first step onto an unreachable non-candidate, so the candidates in ``O``
are exactly those joined, within ``K`` and by the dual adjacency, to a *seed*: a candidate with a
dual neighbour that is unreachable and not a candidate. Hence

    voids = K \ flood_K(seeds),

the flood (breadth first through ``K``) touching only the candidates that leak, and never the
candidates of a sealed cavity; labelling (the number of voids) is only needed on the voids
themselves, and only when their number is asked for.
"""

from __future__ import annotations

import numpy as np
from numba import njit, prange


@njit(parallel=True, cache=True, nogil=True)
def _seed_kernel_reference(cand, occ, full, out):
    """:func:`_seed_kernel` by testing every dual neighbour of every candidate (the former kernel,
    kept as the tests' reference)."""
    n0, n1, n2 = cand.shape
    for i in prange(n0):
        for j in range(n1):
            for k in range(n2):
                if not cand[i, j, k]:
                    out[i, j, k] = False
                    continue
                hit = False
                for di in range(-1, 2):
                    for dj in range(-1, 2):
                        for dk in range(-1, 2):
                            if not full and abs(di) + abs(dj) + abs(dk) != 1:
                                continue
                            a, b, e = i + di, j + dj, k + dk
                            if a < 0 or b < 0 or e < 0 or a >= n0 or b >= n1 or e >= n2:
                                hit = True
                            elif not occ[a, b, e] and not cand[a, b, e]:
                                hit = True
                out[i, j, k] = hit


@njit(cache=True, forceinline=True)
def _leak(cand, occ, a, b, e):
    """Voxel ``(a, b, e)`` is unreachable and not a candidate, or lies outside the array."""
    n0, n1, n2 = cand.shape
    if a < 0 or b < 0 or e < 0 or a >= n0 or b >= n1 or e >= n2:
        return True
    return not occ[a, b, e] and not cand[a, b, e]


@njit(cache=True, forceinline=True)
def _seed_edge(cand, occ, full, i, j, k):
    """:func:`_seed_at` behind its first test, inlined: the voxels of the outer layer are almost never
    candidates, and the call (its 26 bounds-tested reads compiled once) is made only for those that are."""
    return cand[i, j, k] and _seed_at(cand, occ, full, i, j, k)


@njit(cache=True)
def _seed_at(cand, occ, full, i, j, k):
    """:func:`_seed_kernel`'s answer at a candidate voxel (its caller :func:`_seed_edge` tests that),
    every neighbour read with its bounds tested (the voxels of the box's outer layer)."""
    for di in range(-1, 2):
        for dj in range(-1, 2):
            for dk in range(-1, 2):
                if (di != 0 or dj != 0 or dk != 0) and (full or abs(di) + abs(dj) + abs(dk) == 1) \
                        and _leak(cand, occ, i + di, j + dj, k + dk):
                    return True
    return False


@njit(cache=True, forceinline=True)
def _open(cand, occ, i, j, k):
    """Voxel ``(i, j, k)`` (inside the array) is unreachable and not a candidate: ``_leak`` without
    its bounds test and without a branch."""
    return not (occ[i, j, k] | cand[i, j, k])


@njit(parallel=True, cache=True, nogil=True)
def _seed_kernel(cand, occ, full, out):
    """``out``: candidates with a dual neighbour (``full``: 26, else 6) that is unreachable and not a
    candidate, or that lies outside the array (never, for candidates of a margin-padded box). For 26
    neighbours the 3x3x3 neighbourhood is the product of three 3-voxel segments, so "some leaking
    voxel in it" is an or along x, then along y, then along z (nine reads a voxel, not 27); for 6
    neighbours the six are read directly. The voxels off the box's outer layer read their neighbours
    without bounds tests and without branches (their inner loops run in vector lanes); those of the
    outer layer (:func:`_seed_at`) with them. A slice without candidates is written without reads of
    its neighbours."""
    n0, n1, n2 = cand.shape
    for i in prange(n0):
        has = False
        for j in range(n1):
            for k in range(n2):
                if cand[i, j, k]:
                    has = True
                    break
            if has:
                break
        if not has:
            for j in range(n1):
                for k in range(n2):
                    out[i, j, k] = False
            continue
        if i == 0 or i == n0 - 1 or n1 < 3 or n2 < 3:  # the outer layer
            for j in range(n1):
                for k in range(n2):
                    out[i, j, k] = _seed_edge(cand, occ, full, i, j, k)
            continue
        sx = np.empty((n1, n2), np.bool_)  # full: a leak among (i - 1 .. i + 1, j, k)
        if full:
            for j in range(n1):
                for k in range(n2):
                    sx[j, k] = _open(cand, occ, i - 1, j, k) | _open(cand, occ, i, j, k) | _open(cand, occ, i + 1, j, k)
        sy = np.empty(n2, np.bool_)  # ... among (i - 1 .. i + 1, j - 1 .. j + 1, k)
        for j in range(n1):
            if j == 0 or j == n1 - 1:
                for k in range(n2):
                    out[i, j, k] = _seed_edge(cand, occ, full, i, j, k)
                continue
            out[i, j, 0] = _seed_edge(cand, occ, full, i, j, 0)
            out[i, j, n2 - 1] = _seed_edge(cand, occ, full, i, j, n2 - 1)
            if full:
                for k in range(n2):
                    sy[k] = sx[j - 1, k] | sx[j, k] | sx[j + 1, k]
                for k in range(1, n2 - 1):
                    out[i, j, k] = cand[i, j, k] & (sy[k - 1] | sy[k] | sy[k + 1])
            else:
                for k in range(1, n2 - 1):
                    out[i, j, k] = cand[i, j, k] & (
                        _open(cand, occ, i - 1, j, k) | _open(cand, occ, i + 1, j, k)
                        | _open(cand, occ, i, j - 1, k) | _open(cand, occ, i, j + 1, k)
                        | _open(cand, occ, i, j, k - 1) | _open(cand, occ, i, j, k + 1))


@njit(cache=True, nogil=True)
def _flood_kernel(cand, reached, full, n_seed):
    """Grow ``reached`` (the ``n_seed`` seeds on entry) to every candidate joined to it within
    ``cand`` by the dual adjacency (breadth first; each candidate enters the queue once)."""
    n0, n1, n2 = cand.shape
    size = n_seed + 1
    queue = np.empty((size, 3), np.int64)
    head = 0
    tail = 0
    for i in range(n0):
        for j in range(n1):
            for k in range(n2):
                if reached[i, j, k]:
                    queue[tail, 0] = i
                    queue[tail, 1] = j
                    queue[tail, 2] = k
                    tail += 1
    while head < tail:
        i = queue[head, 0]
        j = queue[head, 1]
        k = queue[head, 2]
        head += 1
        for di in range(-1, 2):
            for dj in range(-1, 2):
                for dk in range(-1, 2):
                    if not full and abs(di) + abs(dj) + abs(dk) != 1:
                        continue
                    a, b, e = i + di, j + dj, k + dk
                    if a < 0 or b < 0 or e < 0 or a >= n0 or b >= n1 or e >= n2:
                        continue
                    if cand[a, b, e] and not reached[a, b, e]:
                        reached[a, b, e] = True
                        if tail == size:  # grow the queue (amortised doubling)
                            size *= 2
                            bigger = np.empty((size, 3), np.int64)
                            bigger[:tail] = queue[:tail]
                            queue = bigger
                        queue[tail, 0] = a
                        queue[tail, 1] = b
                        queue[tail, 2] = e
                        tail += 1


@njit(parallel=True, cache=True, nogil=True)
def _count_kernel(mask):
    """The number of True voxels of ``mask``, over x slices in parallel."""
    n0, n1, n2 = mask.shape
    counts = np.zeros(n0, np.int64)
    for i in prange(n0):
        c = 0
        for j in range(n1):
            for k in range(n2):
                if mask[i, j, k]:
                    c += 1
        counts[i] = c
    return counts.sum()


@njit(parallel=True, cache=True, nogil=True)
def _unreached_kernel(cand, reached, out):
    """``out = cand & ~reached`` in one parallel pass; returns the number of such voxels."""
    n0, n1, n2 = cand.shape
    counts = np.zeros(n0, np.int64)
    for i in prange(n0):
        c = 0
        for j in range(n1):
            for k in range(n2):
                v = cand[i, j, k] and not reached[i, j, k]
                out[i, j, k] = v
                if v:
                    c += 1
        counts[i] = c
    return counts.sum()


@njit(parallel=True, cache=True, nogil=True)
def _copy_kernel(src, dst):
    """``dst[...] = src`` (``src`` any layout, e.g. a box cut from a grid), over x slices in parallel."""
    n0, n1, n2 = src.shape
    for i in prange(n0):
        for j in range(n1):
            for k in range(n2):
                dst[i, j, k] = src[i, j, k]


def _contiguous(a: np.ndarray) -> np.ndarray:
    """``np.ascontiguousarray(a, bool)``, the copy (of a non-contiguous box) made in parallel."""
    a = np.asarray(a, dtype=np.bool_)
    if a.flags.c_contiguous:
        return a
    out = np.empty(a.shape, np.bool_)
    if a.size:
        _copy_kernel(a, out)
    return out


def enclosed_voids(cand: np.ndarray, occ: np.ndarray, full: bool) -> tuple[np.ndarray, int]:
    """``(voids, |voids|)`` of the module docstring for the candidates ``cand`` of ``occ`` (both on a
    box whose outer layer holds no candidate); ``full``: the dual adjacency is 26 (else 6)."""
    cand = _contiguous(cand)
    occ = _contiguous(occ)
    reached = np.empty(cand.shape, np.bool_)
    _seed_kernel(cand, occ, full, reached)
    n_seed = int(_count_kernel(reached)) if reached.size else 0
    if n_seed:  # no seed: no candidate leaks, and the serial flood has nothing to visit
        _flood_kernel(cand, reached, full, n_seed)
    out = np.empty(cand.shape, np.bool_)
    n = int(_unreached_kernel(cand, reached, out))
    return out, n
