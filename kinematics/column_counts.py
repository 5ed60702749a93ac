r"""The measures that are one z-interval per column, counted from the set's runs along z (no grid):
the hull volume, the hull underside ``U`` of ``hollowness`` and its sealed part, the column gaps
(definitions in :mod:`kinematics.measures`).

Index units. Column ``(i, j)`` of a grid with ``nz`` layers holds the runs ``[s_q, e_q]`` of the set
``W`` (:mod:`kinematics.run_components`, in increasing z); ``b`` is its first run's start and ``t``
its last run's end (an empty column has neither). The hull ``K`` of the centres meets the column in
the real interval ``zlo <= z <= zhi`` (:func:`kinematics.hull.hull_limits`; ``zlo > zhi`` off its
footprint), so, with ``x^+ = max(x, 0)`` and ``|[p, q] n [s, e]|`` the number of integers in both:

* the hull's voxels ``H(i, j) = {k in [0, nz - 1] : zlo <= k <= zhi} = [a, c]`` with
  ``a = max(0, ceil zlo)``, ``c = min(nz - 1, floor zhi)``: ``|H(i, j)| = (c - a + 1)^+``;
* the underside ``U(i, j) = {k in H(i, j) : k < t, k not in W} = [a, u] \ W`` with
  ``u = min(c, t - 1)``: ``|U(i, j)| = (u - a + 1)^+ - sum_q |[a, u] n [s_q, e_q]|``;
* the gaps ``G(i, j) = [b, t] \ W``: ``|G(i, j)| = t - b + 1 - sum_q (e_q - s_q + 1)``;
* the sealed underside ``|U n S|``, ``S`` the sealed voxels (:func:`kinematics.voids.sealed_box`,
  never in ``W``), is the number of voxels of ``S`` with ``a <= k <= u`` in their column.

A set whose centres are coplanar has no 3-D hull; ``K`` is then ``W`` itself: ``H = W`` and ``U``
is empty (a voxel of ``U`` is not in ``W``).

Cost: one pass over the runs per count (their number grows with the surface, not the volume) and
qhull on the hull's points, where the grid passes they replace (the hull's mask filled and counted,
the underside's mask, the gaps' pass) read or wrote every voxel of the box. The ``*_reference``
functions compute each count from the grid by the definitions (the hull's mask by every facet at
every column, cumulative ors along z): the tests' slow path.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numba import njit, prange

from .hull import PendingHull, hull_limits
from .parallel import KERNEL_LOCK
from .run_components import _paint_runs_kernel

Runs = tuple[np.ndarray, np.ndarray, np.ndarray]


class ColumnRanges(NamedTuple):
    """Per column ``(i, j)`` the z range ``lo[i, j] .. hi[i, j]`` (``lo > hi``: none), and the number of
    voxels of the set in all of them (for the underside, the range less the voxels of ``W``)."""

    lo: np.ndarray
    hi: np.ndarray
    voxels: int


@njit(parallel=True, cache=True, nogil=True)
def _column_ends_kernel(offs, rs, re, kbot, ktop):
    """``kbot``, ``ktop`` (flat, one per column): the first run's start and the last run's end
    (``-1`` in both for an empty column)."""
    for c in prange(kbot.shape[0]):
        q0 = offs[c]
        q1 = offs[c + 1]
        if q1 > q0:
            kbot[c] = rs[q0]
            ktop[c] = re[q1 - 1]
        else:
            kbot[c] = -1
            ktop[c] = -1


def column_ends(runs: Runs, shape: tuple[int, int, int]) -> tuple[np.ndarray, np.ndarray]:
    """``(kbot, ktop)``, each ``(n0, n1)``: every column's lowest and highest index in the set of the
    runs ``runs`` (``-1`` in both for an empty column)."""
    offs, rs, re = runs
    kbot = np.empty(shape[0] * shape[1], np.int64)
    ktop = np.empty(shape[0] * shape[1], np.int64)
    with KERNEL_LOCK:
        _column_ends_kernel(offs, rs, re, kbot, ktop)
    return kbot.reshape(shape[:2]), ktop.reshape(shape[:2])


@njit(parallel=True, cache=True, nogil=True)
def _hull_ranges_kernel(zlo, zhi, i0, j0, nz, lo, hi, counts):
    """``lo``, ``hi`` over the whole grid's columns (set to none beforehand): ``[a, c]`` of the
    module docstring for the columns of the rectangle of ``zlo`` from ``(i0, j0)``; ``counts[i]``:
    the voxels in row ``i`` of the rectangle."""
    ni, nj = zlo.shape
    top = np.float64(nz - 1)
    for i in prange(ni):
        n = 0
        for j in range(nj):
            a = max(0.0, np.ceil(zlo[i, j]))
            c = min(top, np.floor(zhi[i, j]))
            if a <= c:
                lo[i0 + i, j0 + j] = np.int64(a)
                hi[i0 + i, j0 + j] = np.int64(c)
                n += np.int64(c) - np.int64(a) + 1
        counts[i] = n


def _none(shape: tuple[int, int, int]) -> tuple[np.ndarray, np.ndarray]:
    """Ranges ``(lo, hi)`` with no voxel in any column."""
    return np.zeros(shape[:2], np.int64), np.full(shape[:2], -1, np.int64)


def hull_ranges(runs: Runs, shape: tuple[int, int, int]) -> ColumnRanges | None:
    """The hull's voxels ``H`` (module docstring) of the non-empty set of the runs ``runs`` in a grid
    of ``shape``; ``None`` when its centres are coplanar (``K = W``)."""
    return hull_ranges_of(start_hull(runs, shape, background=False), shape)


def start_hull(runs: Runs, shape: tuple[int, int, int], background: bool = True) -> PendingHull:
    """:func:`hull_ranges`'s hull, with qhull started in a thread of its own where ``background``
    (:class:`kinematics.hull.PendingHull`); :func:`hull_ranges_of` finishes it."""
    kbot, ktop = column_ends(runs, shape)
    return PendingHull(kbot, ktop, background=background)


def hull_ranges_of(pending: PendingHull, shape: tuple[int, int, int]) -> ColumnRanges | None:
    """:func:`hull_ranges` of a hull started by :func:`start_hull` (waits for its qhull)."""
    limits = pending.result()
    if limits is None:
        return None
    i0, j0, zlo, zhi = limits
    lo, hi = _none(shape)
    counts = np.zeros(zlo.shape[0], np.int64)
    with KERNEL_LOCK:
        _hull_ranges_kernel(zlo, zhi, i0, j0, shape[2], lo, hi, counts)
    return ColumnRanges(lo, hi, int(counts.sum()))


@njit(parallel=True, cache=True, nogil=True)
def _under_kernel(offs, rs, re, hlo, hhi, lo, hi, counts):
    """``lo``, ``hi`` (flat, one per column): ``[a, u]`` of the module docstring from the hull's
    ``[a, c]`` (``hlo``, ``hhi``) and the column's last run; ``counts[c]``: ``|U|`` of column ``c``."""
    for c in prange(hlo.shape[0]):
        q0 = offs[c]
        q1 = offs[c + 1]
        a = hlo[c]
        u = min(hhi[c], re[q1 - 1] - 1) if q1 > q0 else np.int64(-1)
        if u < a:
            lo[c] = 0
            hi[c] = -1
            counts[c] = 0
            continue
        lo[c] = a
        hi[c] = u
        n = u - a + 1
        for q in range(q0, q1):
            n -= max(0, min(u, re[q]) - max(a, rs[q]) + 1)
        counts[c] = n


def under_ranges(runs: Runs, shape: tuple[int, int, int], hull: ColumnRanges | None) -> ColumnRanges:
    """The underside ``U`` (module docstring) of the set of the runs ``runs`` in a grid of ``shape``,
    its hull's voxels ``hull`` (:func:`hull_ranges`; ``None``: coplanar, ``U`` empty): per column the
    range ``[a, u]``, and ``voxels = |U|`` (the ranges less the voxels of the set)."""
    if hull is None:
        return ColumnRanges(*_none(shape), 0)
    offs, rs, re = runs
    m = shape[0] * shape[1]
    lo = np.empty(m, np.int64)
    hi = np.empty(m, np.int64)
    counts = np.empty(m, np.int64)
    with KERNEL_LOCK:
        _under_kernel(offs, rs, re, hull.lo.reshape(-1), hull.hi.reshape(-1), lo, hi, counts)
    return ColumnRanges(lo.reshape(shape[:2]), hi.reshape(shape[:2]), int(counts.sum()))


@njit(parallel=True, cache=True, nogil=True)
def _gaps_kernel(offs, rs, re, n1, counts):
    """``counts[i]``: ``|G|`` of the columns of x slice ``i``."""
    for i in prange(counts.shape[0]):
        n = 0
        for c in range(i * n1, (i + 1) * n1):
            q0 = offs[c]
            q1 = offs[c + 1]
            if q1 > q0:
                n += re[q1 - 1] - rs[q0] + 1
                for q in range(q0, q1):
                    n -= re[q] - rs[q] + 1
        counts[i] = n


def gap_count(runs: Runs, shape: tuple[int, int, int]) -> int:
    """``sum |G(i, j)|`` (module docstring): the unreachable voxels between reachable ones of their
    column, for the set of the runs ``runs`` in a grid of ``shape``."""
    offs, rs, re = runs
    counts = np.zeros(shape[0], np.int64)
    with KERNEL_LOCK:
        _gaps_kernel(offs, rs, re, shape[1], counts)
    return int(counts.sum())


@njit(parallel=True, cache=True, nogil=True)
def _in_ranges_kernel(lo, hi, sub, i0, j0, k0, counts):
    """``counts[a]``: the voxels of ``sub`` (a box whose corner is ``(i0, j0, k0)`` in the ranges'
    grid, ``k0`` possibly below it) in row ``a`` of the box that lie in their column's range."""
    m0, m1, m2 = sub.shape
    for a in prange(m0):
        n = 0
        for b in range(m1):
            k1 = max(lo[i0 + a, j0 + b] - k0, 0)
            k2 = min(hi[i0 + a, j0 + b] - k0, m2 - 1)
            row = sub[a, b]
            for k in range(k1, k2 + 1):
                n += row[k]
        counts[a] = n


def count_in_ranges(ranges: ColumnRanges, sub: np.ndarray, corner: tuple[int, int, int]) -> int:
    """The voxels of ``sub``, a boolean box whose corner is ``corner`` in the ranges' grid (as
    :func:`kinematics.voids.sealed_box` gives it), that lie in their column's range: ``|U n S|`` for
    the underside's ranges and the sealed voxels, which are never in the set."""
    counts = np.zeros(sub.shape[0], np.int64)
    with KERNEL_LOCK:
        _in_ranges_kernel(ranges.lo, ranges.hi, sub, int(corner[0]), int(corner[1]), int(corner[2]), counts)
    return int(counts.sum())


# -- the definitions on the grid (the tests' slow path) -------------------------------------------


def _grid_of(runs: Runs, shape: tuple[int, int, int]) -> np.ndarray:
    """The set of the runs ``runs`` as a boolean grid of ``shape``."""
    offs, rs, re = runs
    out = np.zeros(shape, np.bool_)
    with KERNEL_LOCK:
        _paint_runs_kernel(offs, rs, re, np.ones(len(rs), np.bool_), shape[1], out)
    return out


def _ranges_of(mask: np.ndarray, count: int) -> ColumnRanges:
    """Each column's lowest and highest index in ``mask`` (one interval per column)."""
    nz = mask.shape[2]
    has = mask.any(axis=2)
    lo = np.where(has, np.argmax(mask, axis=2), 0)
    hi = np.where(has, nz - 1 - np.argmax(mask[:, :, ::-1], axis=2), -1)
    return ColumnRanges(lo.astype(np.int64), hi.astype(np.int64), count)


def hull_ranges_reference(runs: Runs, shape: tuple[int, int, int]) -> ColumnRanges | None:
    """:func:`hull_ranges` from the grid: the column ends by numpy, every facet of the exact hull
    (qhull without joggle) tested at every column, and the mask ``zlo <= k <= zhi`` counted."""
    occ = _grid_of(runs, shape)
    ends = _ranges_of(occ, 0)
    limits = hull_limits(np.where(ends.hi >= 0, ends.lo, -1), ends.hi, raster=False)
    if limits is None:
        return None
    i0, j0, zlo, zhi = limits
    k = np.arange(shape[2])
    mask = np.zeros(shape, np.bool_)
    mask[i0:i0 + zlo.shape[0], j0:j0 + zlo.shape[1]] = (k >= zlo[:, :, None]) & (k <= zhi[:, :, None])
    return _ranges_of(mask, int(np.count_nonzero(mask)))


def _hull_grid(ranges: ColumnRanges, nz: int) -> np.ndarray:
    """The voxels of ``ranges`` as a boolean grid of ``nz`` layers."""
    k = np.arange(nz)
    return (k >= ranges.lo[:, :, None]) & (k <= ranges.hi[:, :, None])


def under_ranges_reference(runs: Runs, shape: tuple[int, int, int], hull: ColumnRanges | None) -> ColumnRanges:
    """:func:`under_ranges` from the grid: covered (a cumulative or from the top) and in the hull,
    less the set; the ranges from the hull's and the covered voxels' column limits."""
    if hull is None:
        return ColumnRanges(*_none(shape), 0)
    occ = _grid_of(runs, shape)
    covered = np.logical_or.accumulate(occ[:, :, ::-1], axis=2)[:, :, ::-1]
    covered[:, :, :-1] = covered[:, :, 1:].copy()
    covered[:, :, -1] = False  # a voxel with a reachable one strictly above it
    span = covered & _hull_grid(hull, shape[2])
    return _ranges_of(span, int(np.count_nonzero(span & ~occ)))


def gap_count_reference(runs: Runs, shape: tuple[int, int, int]) -> int:
    """:func:`gap_count` by cumulative ors along z."""
    occ = _grid_of(runs, shape)
    above = np.logical_or.accumulate(occ[:, :, ::-1], axis=2)[:, :, ::-1]
    below = np.logical_or.accumulate(occ, axis=2)
    return int(np.count_nonzero(above & below & ~occ))


def count_in_ranges_reference(ranges: ColumnRanges, sub: np.ndarray, corner: tuple[int, int, int]) -> int:
    """:func:`count_in_ranges` by painting ``sub`` into the ranges' grid (its part inside it)."""
    n0, n1 = ranges.lo.shape
    nz = int(max(ranges.hi.max(), corner[2] + sub.shape[2])) + 1
    grid = np.zeros((n0, n1, nz), np.bool_)
    i0, j0, k0 = (int(c) for c in corner)
    cut = max(0, -k0)
    grid[i0:i0 + sub.shape[0], j0:j0 + sub.shape[1], k0 + cut:k0 + sub.shape[2]] = sub[:, :, cut:]
    return int(np.count_nonzero(grid & _hull_grid(ranges, nz)))


__all__ = ["ColumnRanges", "column_ends", "hull_ranges", "under_ranges", "gap_count", "count_in_ranges",
           "hull_ranges_reference", "under_ranges_reference", "gap_count_reference", "count_in_ranges_reference"]
