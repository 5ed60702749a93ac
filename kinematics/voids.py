r"""Voids (enclosed cavities) of a voxel set, and the sealed cavities of a set standing on its floor.

Definition. ``W`` is a set of voxels of the grid ``G`` with 6-adjacency (``connectivity=1``) or
26-adjacency (``connectivity=3``); its complement takes the *dual* adjacency (26 for 6, 6 for 26:
:func:`dual_connectivity`). Pad ``G`` with one unreachable layer on every side; the complement
``C = pad(G) \ W`` splits into components, and the one holding the padding is the outside ``O``.
The **voids** are

    voids(W) = C \ O,

the unreachable space enclosed by ``W`` on all sides (not open to any face of the box). With a
solid base layer ``P`` just below the grid's bottom face (the plane the workspace stands on), the
**sealed cavities** are ``voids(W u P)`` restricted to the grid (:func:`sealed_mask`).

Computation (the same set as labelling every component of ``C``, :func:`void_mask_labelled`, the
tests' reference). An unreachable voxel with no reachable voxel on one side along some axis is
joined to the padding by that straight line, so it lies in ``O``. The others, the *candidates*
(:func:`_enclosed_ext_kernel`, one parallel pass that also gives their bounding box), are in ``O``
exactly when they are joined within the candidates to one that leaks (:mod:`kinematics.void_flood`):
the flood never visits a sealed cavity, and the voids are counted (as components of runs,
:mod:`kinematics.run_components`) only when their number is asked for (:func:`_voids`).
"""

from __future__ import annotations

import numpy as np
from numba import njit, prange
from scipy import ndimage as ndi

from .parallel import KERNEL_LOCK
from .run_components import count_components
from .void_flood import _contiguous, enclosed_voids


def _structure(connectivity: int) -> np.ndarray:
    return ndi.generate_binary_structure(3, connectivity)


def dual_connectivity(connectivity: int) -> int:
    """Adjacency of the complement paired with ``connectivity`` (1 <-> 3, i.e. 6 <-> 26)."""
    if connectivity not in (1, 3):
        raise ValueError(f"connectivity = {connectivity!r} is invalid: valid values 1 (6-neighbours) "
                         "or 3 (26-neighbours)")
    return 4 - connectivity


def void_mask_labelled(occupancy: np.ndarray, connectivity: int = 1) -> np.ndarray:
    """:func:`void_mask` by its definition: every component of the padded complement labelled, the
    one holding the padding is the outside (the reference of the tests)."""
    occ = np.asarray(occupancy, dtype=bool)
    comp = np.pad(~occ, 1, constant_values=True)
    lab, _ = ndi.label(comp, structure=_structure(dual_connectivity(connectivity)))
    outside = lab[0, 0, 0]
    voids = (lab != outside) & comp
    return voids[1:-1, 1:-1, 1:-1]


@njit(cache=True, forceinline=True)
def _no_ends(first, last, n):
    """A row of first and last indices along an axis of length ``n`` with no set voxel yet."""
    for k in range(first.shape[0]):
        first[k] = n
        last[k] = -1


@njit(cache=True, forceinline=True)
def _no_extent(e, n1, n2):
    """A slice's candidate extent ``e = (j_lo, j_hi, k_lo, k_hi)`` with no candidate (``j_hi = -1``)."""
    e[0] = n1
    e[1] = -1
    e[2] = n2
    e[3] = -1


@njit(cache=True, forceinline=True)
def _add_row(e, j, rlo, rhi):
    """Grow the slice extent ``e`` by row ``j``'s candidates, ``rlo .. rhi`` along z (none when
    ``rhi < 0``); the rows come in increasing ``j``."""
    if rhi >= 0:
        e[0] = min(e[0], j)
        e[1] = j
        e[2] = min(e[2], rlo)
        e[3] = max(e[3], rhi)


@njit(parallel=True, cache=True, nogil=True)
def _enclosed_ext_kernel(occ, out, ext):
    """``out``: unreachable voxels with reachable ones on both sides along x, along y and along z
    (strictly between the first and the last reachable voxel of each of their three axis lines);
    and each x slice's extent of these candidates, ``ext[i] = (j_lo, j_hi, k_lo, k_hi)``
    (inclusive; ``j_hi = -1``: none in slice ``i``), so their bounding box needs no serial pass over
    the grid. Both passes are parallel: the x ends per ``(j, k)`` over y slices, the rest over x
    slices. Every inner loop runs over ``k`` on a contiguous row, without a branch (the ends and
    extents as minima and maxima of selections), so the compiler puts it in vector lanes."""
    n0, n1, n2 = occ.shape
    N0, N1 = np.int32(n0), np.int32(n1)
    fx = np.empty((n1, n2), np.int32)
    lx = np.empty((n1, n2), np.int32)
    for j in prange(n1):
        fxj = fx[j]
        lxj = lx[j]
        _no_ends(fxj, lxj, n0)
        for i in range(n0):
            i32 = np.int32(i)
            row = occ[i, j]
            for k in range(n2):
                o = row[k]
                fxj[k] = min(fxj[k], i32 if o else N0)
                lxj[k] = i32 if o else lxj[k]
    for i in prange(n0):
        fy = np.full(n2, n1, np.int32)
        ly = np.full(n2, -1, np.int32)
        for j in range(n1):
            j32 = np.int32(j)
            row = occ[i, j]
            for k in range(n2):
                o = row[k]
                fy[k] = min(fy[k], j32 if o else N1)
                ly[k] = j32 if o else ly[k]
        _no_extent(ext[i], n1, n2)
        for j in range(n1):
            row = occ[i, j]
            fz = n2
            lz = -1
            for k in range(n2):
                o = row[k]
                fz = min(fz, k if o else n2)
                lz = max(lz, k if o else -1)
            orow = out[i, j]
            fxj = fx[j]
            lxj = lx[j]
            rlo, rhi = n2, -1
            for k in range(n2):
                v = ((not row[k]) & (fz < k) & (k < lz) & (fy[k] < j) & (j < ly[k]) & (fxj[k] < i)
                     & (i < lxj[k]))
                orow[k] = v
                rlo = min(rlo, k if v else n2)
                rhi = max(rhi, k if v else -1)
            _add_row(ext[i], j, rlo, rhi)


@njit(cache=True, forceinline=True)
def _mark_runs(offs, rs, re, c, v, first, last):
    """Over the voxels ``k`` of column ``c``'s runs: ``first[k] = min(first[k], v)``, ``last[k] = v``
    (the lines' ends, when the columns come in increasing ``v``)."""
    for q in range(offs[c], offs[c + 1]):
        fv = first[rs[q]:re[q] + 1]
        lv = last[rs[q]:re[q] + 1]
        for t in range(fv.shape[0]):  # v grows: the first write is the least, the last the greatest
            fv[t] = min(fv[t], v)
            lv[t] = v


@njit(parallel=True, cache=True, nogil=True)
def _x_ends_runs_kernel(offs, rs, re, n0, n1, fx, lx):
    """The first and last ``i`` of a reachable voxel on each x line ``(j, k)`` (``n0`` and ``-1``:
    none), from the set's runs along z (column ``(i, j)`` holds the runs ``offs[i n1 + j] ..
    offs[i n1 + j + 1] - 1``, from ``rs`` to ``re``; those of
    :class:`kinematics.run_components.RunComponents`): written over the runs' voxels only, in
    parallel over y slices."""
    for j in prange(n1):
        fxj = fx[j]
        lxj = lx[j]
        _no_ends(fxj, lxj, n0)
        for i in range(n0):
            _mark_runs(offs, rs, re, i * n1 + j, np.int32(i), fxj, lxj)


def x_ends(runs: tuple, shape: tuple[int, ...]) -> tuple[np.ndarray, np.ndarray]:
    """``(fx, lx)``, each (n1, n2) int32: the first and last ``i`` of a voxel of the set on each x line
    ``(j, k)`` (``n0`` and ``-1``: none), from the set's runs along z (:func:`_x_ends_runs_kernel`)."""
    n0, n1, n2 = (int(n) for n in shape)
    fx = np.empty((n1, n2), np.int32)
    lx = np.empty((n1, n2), np.int32)
    with KERNEL_LOCK:
        _x_ends_runs_kernel(*runs, n0, n1, fx, lx)
    return fx, lx


def floored_x_ends(ends: tuple[np.ndarray, np.ndarray], n0: int) -> tuple[np.ndarray, np.ndarray]:
    """The x ends (:func:`x_ends`) of the set on its base layer (:func:`_floored_runs`) from the set's
    own: the set moved up one layer keeps each line's ends, and every line of the base layer is full
    (``0`` to ``n0 - 1``). The same numbers as computed from the floored set's runs (tested), for the
    copy of two small tables instead of a pass over every voxel of the set."""
    fx, lx = ends
    n1, n2 = fx.shape
    ffx = np.empty((n1, n2 + 1), np.int32)
    flx = np.empty((n1, n2 + 1), np.int32)
    ffx[:, 0], flx[:, 0] = 0, n0 - 1
    ffx[:, 1:], flx[:, 1:] = fx, lx
    return ffx, flx


@njit(cache=True, forceinline=True)
def _y_ends_runs(offs, rs, re, i, n1, fy, ly):
    """:func:`_x_ends_runs_kernel` along y in slice ``i``: ``fy[k]``, ``ly[k]`` (rows of ``n1``, ``-1``)."""
    _no_ends(fy, ly, n1)
    for j in range(n1):
        _mark_runs(offs, rs, re, i * n1 + j, np.int32(j), fy, ly)


@njit(parallel=True, cache=True, nogil=True)
def _enclosed_runs_kernel(offs, rs, re, n1, n2, fx, lx, out, ext):
    """:func:`_enclosed_ext_kernel`'s ``out`` and ``ext`` from the set's runs along z
    (:func:`_x_ends_runs_kernel`'s ``fx``, ``lx``): a candidate lies in a gap between two runs of its
    column (unreachable and strictly between the column's first and last reachable voxel), so only the
    gaps are tested and written; ``out`` comes cleared (``np.zeros``: the pages no gap touches are
    never written). The reads and writes grow with the set's voxels and its gaps, not with the grid."""
    n0 = ext.shape[0]
    for i in prange(n0):
        fy = np.empty(n2, np.int32)
        ly = np.empty(n2, np.int32)
        _y_ends_runs(offs, rs, re, i, n1, fy, ly)
        _no_extent(ext[i], n1, n2)
        for j in range(n1):
            c = i * n1 + j
            fxj = fx[j]
            lxj = lx[j]
            orow = out[i, j]
            rlo, rhi = n2, -1
            for q in range(offs[c], offs[c + 1] - 1):  # the gap between runs q and q + 1
                for k in range(re[q] + 1, rs[q + 1]):
                    v = (fy[k] < j) & (j < ly[k]) & (fxj[k] < i) & (i < lxj[k])
                    orow[k] = v
                    rlo = min(rlo, k if v else n2)
                    rhi = max(rhi, k if v else -1)
            _add_row(ext[i], j, rlo, rhi)


@njit(parallel=True, cache=True, nogil=True)
def _paint_box_kernel(offs, rs, re, n1, i0, j0, k0, out):
    """The set's voxels (its runs) inside the box of ``out`` (a cleared array, its corner at
    ``(i0, j0, k0)``)."""
    m0, m1, m2 = out.shape
    for a in prange(m0):
        for b in range(m1):
            c = (i0 + a) * n1 + j0 + b
            orow = out[a, b]
            for q in range(offs[c], offs[c + 1]):
                for k in range(max(rs[q], k0), min(re[q] + 1, k0 + m2)):
                    orow[k - k0] = True


@njit(cache=True, nogil=True)
def _floored_runs(offs, rs, re):
    """The runs of the set on its base layer (:func:`_floored_kernel`: one layer below ``k = 0``,
    every voxel set) from the set's runs: each run moved up by one, and the base voxel joined to a
    run that starts at ``k = 0`` or a run of its own."""
    n = offs.shape[0] - 1
    offs2 = np.empty(n + 1, np.int64)
    offs2[0] = 0
    for c in range(n):
        a, b = offs[c], offs[c + 1]
        offs2[c + 1] = offs2[c] + (b - a) + (0 if b > a and rs[a] == 0 else 1)
    rs2 = np.empty(offs2[n], np.int64)
    re2 = np.empty(offs2[n], np.int64)
    for c in range(n):
        a, b = offs[c], offs[c + 1]
        p = offs2[c]
        rs2[p] = 0
        if b > a and rs[a] == 0:
            re2[p] = re[a] + 1
            a += 1
        else:
            re2[p] = 0
        p += 1
        for q in range(a, b):
            rs2[p] = rs[q] + 1
            re2[p] = re[q] + 1
            p += 1
    return offs2, rs2, re2


@njit(parallel=True, cache=True, nogil=True)
def _paste_kernel(sub, lo0, lo1, lo2, out):
    """``out[...] = False``, then ``sub`` written with its corner at ``(lo0, lo1, lo2)`` (its part
    inside ``out`` along z: ``lo2`` may be negative), in one parallel pass over the x slices of
    ``out`` (a fresh grid: its pages are first touched by the threads)."""
    n0, n1, n2 = out.shape
    m0, m1, m2 = sub.shape
    for i in prange(n0):
        for j in range(n1):
            for k in range(n2):
                out[i, j, k] = False
        if lo0 <= i < lo0 + m0:
            for j in range(m1):
                for k in range(max(0, -lo2), min(m2, n2 - lo2)):
                    out[i, lo1 + j, lo2 + k] = sub[i - lo0, j, k]


@njit(parallel=True, cache=True, nogil=True)
def _floored_kernel(occ, out):
    """``out = concatenate([ones(n0, n1, 1), occ], axis=2)`` (the grid on its base layer), over x
    slices in parallel."""
    n0, n1, n2 = occ.shape
    for i in prange(n0):
        for j in range(n1):
            out[i, j, 0] = True
            for k in range(n2):
                out[i, j, k + 1] = occ[i, j, k]


@njit(parallel=True, cache=True, nogil=True)
def _open_labels_kernel(cand, lab, occ, full, n_labels):
    """Labels of ``cand`` (the candidates' components) with a dual neighbour that is unreachable and
    not a candidate: those components reach the outside (``full``: 26 neighbours, else 6). Threads
    only ever set entries of ``opened`` to True."""
    n0, n1, n2 = cand.shape
    opened = np.zeros(n_labels + 1, np.bool_)
    for i in prange(n0):
        for j in range(n1):
            for k in range(n2):
                c = lab[i, j, k]
                if c == 0 or opened[c]:
                    continue
                for di in range(-1, 2):
                    for dj in range(-1, 2):
                        for dk in range(-1, 2):
                            if not full and abs(di) + abs(dj) + abs(dk) != 1:
                                continue
                            a, b, e = i + di, j + dj, k + dk
                            if a < 0 or b < 0 or e < 0 or a >= n0 or b >= n1 or e >= n2:
                                opened[c] = True  # pragma: no cover - candidates never touch the edge
                            elif not occ[a, b, e] and not cand[a, b, e]:
                                opened[c] = True
    return opened


def _box_of(ext: np.ndarray) -> tuple | None:
    """The candidates' bounding box grown by one voxel (the neighbours the tests look at; candidates
    never lie on the grid's edge) from the slice extents ``ext``, or ``None`` when there is none."""
    rows = np.flatnonzero(ext[:, 1] >= 0)
    if not rows.size:
        return None
    e = ext[rows]
    lo = [int(rows[0]), int(e[:, 0].min()), int(e[:, 2].min())]
    hi = [int(rows[-1]) + 1, int(e[:, 1].max()) + 1, int(e[:, 3].max()) + 1]
    return tuple(slice(a - 1, b + 1) for a, b in zip(lo, hi))


def _candidates_box(occupancy: np.ndarray | None, runs: tuple | None = None,
                    shape: tuple[int, int, int] | None = None,
                    ends: tuple[np.ndarray, np.ndarray] | None = None) -> tuple[np.ndarray, np.ndarray, tuple] | None:
    """``(occ, candidates, box)``: the unreachable voxels enclosed along all three axes and the set,
    both cut to the candidates' bounding box grown by one voxel (:func:`_box_of`; contiguous arrays of
    its shape), and the box; ``None`` when there is no candidate.

    From the grid ``occupancy`` (:func:`_enclosed_ext_kernel`), or from ``runs``, the set's runs
    ``(offs, rs, re)``, when the caller holds them (the same voxels; ``occupancy`` may then be ``None``
    with ``shape`` the grid's): the candidates written only in the runs' gaps
    (:func:`_enclosed_runs_kernel`) and the set's voxels in the box painted from its runs
    (:func:`_paint_box_kernel`), so no grid is cleared voxel by voxel and none is built for the set.
    ``ends``: the set's x ends (:func:`x_ends`) with ``runs``, when the caller holds them."""
    if runs is None:
        occ = np.ascontiguousarray(occupancy, dtype=np.bool_)
        if not occ.size:
            return None
        cand = np.empty(occ.shape, np.bool_)
        ext = np.empty((occ.shape[0], 4), np.int64)
        with KERNEL_LOCK:
            _enclosed_ext_kernel(occ, cand, ext)
        box = _box_of(ext)
        if box is None:
            return None
        with KERNEL_LOCK:
            return _contiguous(occ[box]), _contiguous(cand[box]), box
    if shape is None:
        assert occupancy is not None, "the grid or its shape"
        dims = tuple(int(n) for n in np.shape(occupancy))
    else:
        dims = tuple(int(n) for n in shape)
    n0, n1, n2 = dims
    if not n0 * n1 * n2:
        return None
    offs, rs, re = runs
    fx, lx = x_ends(runs, dims) if ends is None else ends
    ext = np.empty((n0, 4), np.int64)
    cand = np.zeros((n0, n1, n2), np.bool_)
    with KERNEL_LOCK:
        _enclosed_runs_kernel(offs, rs, re, n1, n2, fx, lx, cand, ext)
    box = _box_of(ext)
    if box is None:
        return None
    occ_box = np.zeros(tuple(b.stop - b.start for b in box), np.bool_)
    with KERNEL_LOCK:
        _paint_box_kernel(offs, rs, re, n1, *(b.start for b in box), occ_box)
        return occ_box, _contiguous(cand[box]), box


def _voids_labelled_candidates(occupancy: np.ndarray, connectivity: int) -> tuple[np.ndarray, int]:
    """:func:`_voids` by labelling every candidate component and testing each for a leak (the former
    path, kept as a reference: the same set and number)."""
    found = _candidates_box(occupancy)
    if found is None:
        return np.zeros(np.shape(occupancy), np.bool_), 0
    occ, sub, box = found
    lab, n = ndi.label(sub, structure=_structure(dual_connectivity(connectivity)))
    with KERNEL_LOCK:
        opened = _open_labels_kernel(sub, lab, occ, dual_connectivity(connectivity) == 3, n)
    keep = ~opened
    keep[0] = False
    voids = np.zeros(np.shape(occupancy), np.bool_)
    voids[box] = keep[lab]
    return voids, int(keep.sum())


def _void_box(occupancy: np.ndarray | None, connectivity: int, runs: tuple | None = None,
              shape: tuple[int, int, int] | None = None,
              ends: tuple[np.ndarray, np.ndarray] | None = None) -> tuple[np.ndarray, tuple] | None:
    """``(voids, box)``: the voids inside the box that bounds them (``None``: no void), the
    candidates (:func:`_candidates_box`, with its ``runs``, ``shape`` and ``ends``) less the flood of
    :mod:`kinematics.void_flood` from those that leak, which never visits a sealed cavity."""
    found = _candidates_box(occupancy, runs, shape, ends)
    if found is None:
        return None
    occ, cand, box = found
    with KERNEL_LOCK:
        sub, n_void = enclosed_voids(cand, occ, dual_connectivity(connectivity) == 3)
    return (sub, box) if n_void else None


def _void_set(occupancy: np.ndarray, connectivity: int, runs: tuple | None = None,
              ends: tuple[np.ndarray, np.ndarray] | None = None) -> tuple[np.ndarray, tuple | None]:
    """``(void_mask, box)`` of :func:`_voids` without their number (:func:`_void_box` on the grid's
    shape; ``box`` bounds the voids, ``None``: no void)."""
    found = _void_box(occupancy, connectivity, runs, None, ends)
    if found is None:
        return np.zeros(np.shape(occupancy), np.bool_), None
    sub, box = found
    voids = np.empty(np.shape(occupancy), np.bool_)
    with KERNEL_LOCK:
        _paste_kernel(sub, box[0].start, box[1].start, box[2].start, voids)
    return voids, box


def _voids(occupancy: np.ndarray, connectivity: int, runs: tuple | None = None,
           ends: tuple[np.ndarray, np.ndarray] | None = None) -> tuple[np.ndarray, int]:
    """``(void_mask, number of voids)`` without labelling the whole complement.

    An unreachable voxel with no reachable voxel on one side along some axis is joined to the
    padding by that straight line of unreachable voxels (a path for 6 and for 26 neighbours), so it
    is outside. The others, the candidates (:func:`_enclosed_ext_kernel`), are outside exactly when they
    are joined within the candidates to one with a dual neighbour that is unreachable and not a
    candidate (:func:`_void_set`); only the voids left are counted, as components of runs
    (:mod:`kinematics.run_components`; each void component is one candidate component: distinct
    candidate components are not adjacent). ``runs``: the set's runs ``(offs, rs, re)``, when the
    caller holds them (:func:`_candidates_box`), with their x ends ``ends`` (:func:`x_ends`) if it
    holds those too.
    """
    voids, box = _void_set(occupancy, connectivity, runs, ends)
    if box is None:
        return voids, 0
    return voids, count_components(voids[box], dual_connectivity(connectivity))


def void_mask(occupancy: np.ndarray, connectivity: int = 1) -> np.ndarray:
    """Voxels of the enclosed voids (complement components not connected to the padded outside);
    computed by :func:`_void_set` (no labelling), the same set as :func:`void_mask_labelled`."""
    return _void_set(occupancy, connectivity)[0]


def sealed_box(occupancy: np.ndarray, connectivity: int = 1, floor: bool = True,
               runs: tuple | None = None,
               ends: tuple[np.ndarray, np.ndarray] | None = None) -> tuple[np.ndarray, tuple[int, int, int]] | None:
    """:func:`sealed_mask` inside a box that bounds it: ``(sub, corner)``, the sealed voxels with the
    box's corner at ``corner`` in the grid (``None``: none). With ``floor`` the box is the floored
    grid's, one layer lower: its corner's ``k`` may be ``-1`` (that layer is the base, never sealed);
    only its part inside the grid counts. ``runs``: the set's runs, when the caller holds them (the
    floored set's runs built from them, :func:`_floored_runs`: no floored grid), and ``ends`` their
    x ends (:func:`x_ends`) when it holds those too (the floored set's from them,
    :func:`floored_x_ends`)."""
    occ = np.asarray(occupancy, dtype=bool)
    n0, n1, n2 = occ.shape
    if runs is None:
        ends = None
    if not floor:
        found = _void_box(occ, connectivity, runs, None, ends)
        shift = 0
    else:
        if runs is not None:
            floored = None
            with KERNEL_LOCK:
                runs = _floored_runs(*runs)
            if ends is not None:
                ends = floored_x_ends(ends, n0)
        else:
            floored = np.empty((n0, n1, n2 + 1), np.bool_)
            if floored.size:
                with KERNEL_LOCK:
                    _floored_kernel(np.ascontiguousarray(occ), floored)
        found = _void_box(floored, connectivity, runs, (n0, n1, n2 + 1), ends)
        shift = 1  # the floored grid's layer k + 1 is the grid's layer k
    if found is None:
        return None
    sub, box = found
    return sub, (box[0].start, box[1].start, box[2].start - shift)


def sealed_mask(occupancy: np.ndarray, connectivity: int = 1, floor: bool = True,
                runs: tuple | None = None) -> np.ndarray:
    """Unreachable voxels enclosed by the workspace together with the base plane.

    The voids of ``W u P`` where ``P`` is a solid layer just below the grid's bottom face
    (``floor=True``) -- the plane the workspace stands on; with ``floor=False`` the voids of ``W``.
    ``runs``: the runs ``(offs, rs, re)`` of ``W``, when the caller holds them (the candidates from
    them, :func:`_candidates_box`; the same set).
    """
    found = sealed_box(occupancy, connectivity, floor, runs)
    if found is None:
        return np.zeros(np.shape(occupancy), np.bool_)
    sub, corner = found
    sealed = np.empty(np.shape(occupancy), np.bool_)
    with KERNEL_LOCK:
        _paste_kernel(sub, *corner, sealed)
    return sealed
