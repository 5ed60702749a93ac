r"""Connected components of a voxel set, labelled in parallel by x slabs (union-find, then merge).

Definition: voxels ``u, v`` of the set ``X`` are adjacent when ``max_a |u_a - v_a| <= 1`` and
``sum_a |u_a - v_a| <= c`` (``c = connectivity``: 1 gives 6 neighbours, 3 gives 26), and a
component is a class of the transitive closure of adjacency -- the components
``scipy.ndimage.label(X, generate_binary_structure(3, c))`` finds (the same partition, numbered
differently: here in the order of each component's first voxel in raster order, as scipy does).

Computation. Each slab of x layers joins, in its own thread, every voxel to its already-visited
neighbours inside the slab (a union-find forest over flat indices whose trees never leave the slab:
a root is always the smallest index of its tree); the layers where two slabs meet are then joined
serially (a plane's worth of work per slab); the roots are found in parallel and numbered in raster
order of the roots, the smallest index of each component, which is its first voxel.
"""

from __future__ import annotations

import numba
import numpy as np
from numba import njit, prange
from scipy import ndimage as ndi

from .parallel import KERNEL_LOCK


@njit(cache=True, inline="always")
def _find(parent, v):
    while parent[v] != v:
        v = parent[v]
    return v


@njit(cache=True, inline="always")
def _find_halving(parent, v):
    while parent[v] != v:
        parent[v] = parent[parent[v]]
        v = parent[v]
    return v


@njit(cache=True, inline="always")
def _union(parent, a, b):
    ra = _find_halving(parent, a)
    rb = _find_halving(parent, b)
    if ra < rb:
        parent[rb] = ra
    elif rb < ra:
        parent[ra] = rb


@njit(cache=True, inline="always")
def _join_back(occ, parent, i, j, k, i_lo, offs):
    """Join voxel ``(i, j, k)`` to its set neighbours that precede it in raster order (the offsets
    ``offs``), at x >= ``i_lo``: it joins the first one's tree, and any other tree found is linked to
    the smaller of the two roots."""
    n0, n1, n2 = occ.shape
    v = (i * n1 + j) * n2 + k
    r = np.int32(-1)
    for q in range(offs.shape[0]):
        a = i + offs[q, 0]
        b = j + offs[q, 1]
        e = k + offs[q, 2]
        if a < i_lo or b < 0 or b >= n1 or e < 0 or e >= n2 or not occ[a, b, e]:
            continue
        ru = _find_halving(parent, np.int32((a * n1 + b) * n2 + e))
        if r < 0:
            r = ru
        elif ru < r:
            parent[r] = ru
            r = ru
        elif r < ru:
            parent[ru] = r
    parent[v] = v if r < 0 else r  # r < v: a root is the smallest index of its tree


#: the neighbours that precede a voxel in raster order: 3 of the 6 (face), 13 of the 26
_BACK6 = np.array([[-1, 0, 0], [0, -1, 0], [0, 0, -1]], np.int64)
_BACK26 = np.array([[di, dj, dk] for di in (-1, 0) for dj in (-1, 0, 1) for dk in (-1, 0, 1)
                    if di < 0 or dj < 0 or (dj == 0 and dk < 0)], np.int64)


@njit(parallel=True, cache=True, nogil=True)
def _label_kernel(occ, offs, n_slabs, parent, labels):
    """Labels 1..n of the components of ``occ`` (0 off the set) into ``labels``; returns ``n``."""
    n0, n1, n2 = occ.shape
    plane = n1 * n2
    step = (n0 + n_slabs - 1) // n_slabs
    for s in prange(n_slabs):
        i_lo = s * step
        for i in range(i_lo, min(n0, i_lo + step)):
            for j in range(n1):
                for k in range(n2):
                    if occ[i, j, k]:
                        _join_back(occ, parent, i, j, k, i_lo, offs)
    for s in range(1, n_slabs):  # the layers where two slabs meet: x = i_lo against x = i_lo - 1
        i = s * step
        if i >= n0:
            break
        for j in range(n1):
            for k in range(n2):
                if occ[i, j, k]:
                    v = np.int32((i * n1 + j) * n2 + k)
                    for q in range(offs.shape[0]):
                        if offs[q, 0] != -1:
                            continue
                        b = j + offs[q, 1]
                        e = k + offs[q, 2]
                        if b < 0 or b >= n1 or e < 0 or e >= n2 or not occ[i - 1, b, e]:
                            continue
                        ra = _find_halving(parent, v)
                        rb = _find_halving(parent, np.int32(((i - 1) * n1 + b) * n2 + e))
                        if ra < rb:
                            parent[rb] = ra
                        elif rb < ra:
                            parent[ra] = rb
    roots = np.zeros(n0, np.int64)
    for i in prange(n0):  # each voxel's root (read-only on parent), and the roots of each x layer
        c = 0
        for j in range(n1):
            for k in range(n2):
                q = i * plane + j * n2 + k
                if occ[i, j, k]:
                    r = _find(parent, np.int32(q))
                    labels[q] = r
                    if r == q:
                        c += 1
                else:
                    labels[q] = -1
        roots[i] = c
    first = np.zeros(n0, np.int64)
    for i in range(1, n0):
        first[i] = first[i - 1] + roots[i - 1]
    n = first[n0 - 1] + roots[n0 - 1]
    for i in prange(n0):  # number the roots in raster order (a root is its tree's smallest index)
        c = first[i]
        for q in range(i * plane, (i + 1) * plane):
            if labels[q] == q:
                c += 1
                parent[q] = c
    for i in prange(n0):
        for q in range(i * plane, (i + 1) * plane):
            r = labels[q]
            labels[q] = parent[r] if r >= 0 else 0
    return n


def label_components(occupancy: np.ndarray, connectivity: int = 1) -> tuple[np.ndarray, int]:
    """``(labels, n)`` as ``scipy.ndimage.label(occupancy, generate_binary_structure(3,
    connectivity))`` gives them (the same labels: both number the components in the raster order
    of their first voxels), for ``connectivity`` 1 or 3; scipy itself for grids of 2^31 voxels or
    more, or other connectivities."""
    occ = np.ascontiguousarray(occupancy, dtype=np.bool_)
    if occ.ndim != 3 or occ.size >= 2 ** 31 - 1 or connectivity not in (1, 3) or occ.size == 0:
        return ndi.label(occ, structure=ndi.generate_binary_structure(occ.ndim, connectivity))
    parent = np.empty(occ.size, np.int32)
    labels = np.empty(occ.size, np.int32)
    n_slabs = max(1, min(occ.shape[0], 4 * numba.get_num_threads()))
    with KERNEL_LOCK:
        n = _label_kernel(occ, _BACK26 if connectivity == 3 else _BACK6, n_slabs, parent, labels)
    return labels.reshape(occ.shape), int(n)
