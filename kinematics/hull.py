"""The convex hull of a voxel set as a voxel mask: the voxels whose centre lies in ``K = conv{c(v) :
v in W}``, the hull of the reachable voxels' centres (used by :mod:`kinematics.measures` for
``hull_volume``, ``solidity`` and the hull hollowness).

In index units a column ``(i, j)`` meets ``K`` in the interval ``zlo(i, j) <= z <= zhi(i, j)``, where
``zhi`` is the upper surface of ``K`` over the column and ``zlo`` its lower one (empty off the
footprint, the projection of ``K``). ``K`` is the hull of each occupied column's lowest and highest
centre, and only those that are strict vertices of the 2-D hull of the column ends along their x
line, y line and both diagonals can be its vertices (:func:`hull_points`); qhull triangulates its
surface. The upper surface over the footprint is the union of the triangles whose outward normal
points up (the graph of a concave function), the lower surface of those whose normal points down,
so each column takes its limits from the triangles whose projection covers its centre
(:func:`_raster_kernel`; exact integer tests on these lattice points). The reference,
``hull_mask(..., raster=False)``, tests every facet's inequality ``n . p + d <= 1e-7`` at every
column (:func:`hull_columns`): the same mask, since a facet plane through no lattice point of a column
passes at least ``1 / |n_z|`` (about ``1e-5``) from it.

For the raster qhull runs with its input joggled (``QJ``, :data:`QHULL_RASTER`), which spares it the
merging of the many coplanar lattice points (about half its time). The triangles it returns are
facets of the hull of the points moved by at most ``~1e-8`` index units, with the raster's heights
and edge tests computed exactly from the original lattice points. Such a triangle lies on a facet of
``K``: its corners are points of the set, and a triangle of set points that cut into ``K`` would sit
a finite distance (``>= 1 / |n|`` for integer normals ``n``, about ``1e-5``) below some set point, which
the joggle cannot close. The only triangles that change are vertical ones and slivers of collinear
points, which cover no column (exact integer normal ``n_z = 0``), and the triangulation of a facet,
whose union is the facet either way: the same mask as the exact hull (tested against it and against
a brute-force half-space test on small sets).
"""

from __future__ import annotations

import threading

import numpy as np
from numba import njit, prange
from scipy.spatial import ConvexHull, QhullError

from .parallel import KERNEL_LOCK

#: qhull's options for :func:`hull_mask`'s raster: the input joggled (module docstring).
QHULL_RASTER = "QJ"


@njit(cache=True, forceinline=True)
def _facet_clip(eq, f, i, j, tol, lo, hi):
    """Column ``(i, j)``'s z-interval ``[lo, hi]`` cut by facet ``f`` (``n . p + d <= 0`` inside):
    ``(lo, hi, outside)``, ``outside`` (with ``lo > hi``) when a vertical facet leaves the column out."""
    s = eq[f, 0] * i + eq[f, 1] * j + eq[f, 3] - tol
    nz = eq[f, 2]
    if nz > 1e-12:
        v = -s / nz
        if v < hi:
            hi = v
    elif nz < -1e-12:
        v = -s / nz
        if v > lo:
            lo = v
    elif s > 0.0:
        return np.inf, -np.inf, True
    return lo, hi, False


@njit(parallel=True, cache=True, nogil=True)
def _hull_columns_kernel(nx, ny, eq, tol, zlo, zhi):
    """Per column ``(i, j)`` the z-interval ``[zlo, zhi]`` (index units) inside the hull ``eq``.

    ``eq`` rows are qhull facet equations ``n . p + d <= 0`` (inside); an empty column gets
    ``zlo > zhi``.
    """
    nf = eq.shape[0]
    for c in prange(nx * ny):
        i = c // ny
        j = c - i * ny
        lo = -np.inf
        hi = np.inf
        for f in range(nf):
            lo, hi, outside = _facet_clip(eq, f, i, j, tol, lo, hi)
            if outside:
                break
        zlo[i, j] = lo
        zhi[i, j] = hi


def hull_columns(nx: int, ny: int, eq: np.ndarray, tol: float) -> tuple[np.ndarray, np.ndarray]:
    """``(zlo, zhi)`` of :func:`_hull_columns_kernel` for the ``nx x ny`` columns: every facet tested
    at every column (the reference of :func:`hull_mask`'s raster)."""
    zlo = np.empty((nx, ny))
    zhi = np.empty((nx, ny))
    with KERNEL_LOCK:
        _hull_columns_kernel(nx, ny, np.ascontiguousarray(eq, dtype=np.float64), tol, zlo, zhi)
    return zlo, zhi


@njit(parallel=True, cache=True, nogil=True)
def _column_ends_kernel(occ, kbot, ktop):
    """Per column the lowest and highest reachable index (``-1`` in both for an empty column)."""
    nx, ny, nz = occ.shape
    for i in prange(nx):
        for j in range(ny):
            row = occ[i, j]
            lo = nz
            hi = -1
            for k in range(nz):  # no branch: vector lanes
                o = row[k]
                lo = min(lo, k if o else nz)
                hi = max(hi, k if o else -1)
            kbot[i, j] = lo if hi >= 0 else -1
            ktop[i, j] = hi


@njit(cache=True, forceinline=True)
def _chain_flags(idx, val, m, upper, stack, flag):
    """Strict vertices of the upper (``upper``) or lower chain of the points ``(idx[q], val[q])``,
    ``q < m``, sorted by ``idx`` (Andrew's monotone chain; a point on or beyond the segment of its
    neighbours is popped): ``flag[q]`` set for each."""
    top = 0
    for q in range(m):
        while top >= 2:
            a = stack[top - 2]
            b = stack[top - 1]
            cross = (idx[b] - idx[a]) * (val[q] - val[a]) - (val[b] - val[a]) * (idx[q] - idx[a])
            if (cross >= 0) if upper else (cross <= 0):
                top -= 1
            else:
                break
        stack[top] = q
        top += 1
    for q in range(top):
        flag[stack[q]] = True


@njit(parallel=True, cache=True, nogil=True)
def _line_extreme_kernel(kbot, ktop, axis, keep_bot, keep_top):
    """Clear ``keep_top[i, j]`` (``keep_bot``) where column ``(i, j)``'s highest (lowest) centre is
    not a strict vertex of the 2-D hull of the column ends along its line of columns: x lines for
    ``axis == 0``, y lines for 1, the diagonals ``i + j`` constant for 2 and ``i - j`` constant for 3
    (abscissa ``i``, an affine map of the distance along the line). Such a point lies in the hull of
    other points of the set, so the 3-D hull does not need it (a vertex of the 3-D hull is extreme in
    every subset)."""
    nx, ny = kbot.shape
    n_lines = ny if axis == 0 else (nx if axis == 1 else nx + ny - 1)
    n_along = nx if axis != 1 else ny
    for ln in prange(n_lines):
        line = np.int64(ln)
        idx = np.empty(n_along, np.int64)
        top = np.empty(n_along, np.int64)
        bot = np.empty(n_along, np.int64)
        stack = np.empty(n_along, np.int64)
        f_top = np.zeros(n_along, np.bool_)
        f_bot = np.zeros(n_along, np.bool_)
        m = 0
        for p in range(n_along):
            i, j = _line_column(np.int64(p), line, axis, ny)
            if j < 0 or j >= ny:
                continue
            if ktop[i, j] >= 0:
                idx[m] = p
                top[m] = ktop[i, j]
                bot[m] = kbot[i, j]
                m += 1
        _chain_flags(idx, top, m, True, stack, f_top)
        _chain_flags(idx, bot, m, False, stack, f_bot)
        for q in range(m):
            i, j = _line_column(idx[q], line, axis, ny)
            if not f_top[q]:
                keep_top[i, j] = False
            if not f_bot[q] and not (f_top[q] and top[q] == bot[q]):  # a one-point column is both ends
                keep_bot[i, j] = False


@njit(cache=True, forceinline=True)
def _line_column(p, line, axis, ny):
    """Column ``(i, j)`` of point ``p`` of line ``line`` of :func:`_line_extreme_kernel` (``j`` may fall
    off the grid on a diagonal)."""
    if axis == 0:
        return p, line
    if axis == 1:
        return line, p
    if axis == 2:
        return p, line - p
    return p, p - line + ny - 1


def hull_points(kbot: np.ndarray, ktop: np.ndarray, extreme: bool = True) -> np.ndarray:
    """The points whose convex hull is that of the reachable centres: each occupied column's lowest
    and highest centre (index units, the lowest first, the highest only where it differs), and with
    ``extreme`` (default) only those that are strict vertices of the 2-D hull of their x line's and of
    their y line's column ends (:func:`_line_extreme_kernel`; every vertex of the 3-D hull stays, so
    the hull is the same polytope from far fewer points)."""
    col = ktop >= 0
    keep_bot = col.copy()
    keep_top = col & (ktop != kbot)
    if extreme:
        kb = np.ascontiguousarray(kbot, dtype=np.int64)
        kt = np.ascontiguousarray(ktop, dtype=np.int64)
        with KERNEL_LOCK:
            for axis in range(4):
                _line_extreme_kernel(kb, kt, axis, keep_bot, keep_top)
    ib, jb = np.nonzero(keep_bot)
    it, jt = np.nonzero(keep_top)
    return np.concatenate([np.stack([ib, jb, kbot[ib, jb]], 1),
                           np.stack([it, jt, ktop[it, jt]], 1)]).astype(np.float64)


def hull_mask(occupancy: np.ndarray, raster: bool = True, extreme: bool = True) -> np.ndarray:
    """Voxels whose centre lies in the convex hull of the reachable voxels' centres.

    The hull is that of each occupied column's lowest and highest centre (the same polytope as
    the hull of all centres, from fewer points). A workspace whose centres are coplanar (no
    3-D hull) returns the workspace itself. ``raster`` (default) takes each column's limits from the
    facets whose projection covers it (:func:`_raster_kernel`); ``raster=False`` tests every facet
    at every column (:func:`hull_columns`; the same mask). ``extreme=False`` gives qhull every
    column end instead of the extreme ones of :func:`hull_points` (the same polytope, the same mask).
    """
    occ = np.asarray(occupancy, dtype=bool)
    if not occ.any():
        return np.zeros_like(occ)
    nx, ny, nz = occ.shape
    kbot = np.empty((nx, ny), np.int64)
    ktop = np.empty((nx, ny), np.int64)
    with KERNEL_LOCK:
        _column_ends_kernel(np.ascontiguousarray(occ), kbot, ktop)
    limits = hull_limits(kbot, ktop, raster, extreme)
    if limits is None:
        return occ.copy()
    out = np.zeros_like(occ)
    with KERNEL_LOCK:
        _hull_fill_kernel(limits[2], limits[3], limits[0], limits[1], out)
    return out


def hull_limits(kbot: np.ndarray, ktop: np.ndarray, raster: bool = True,
                extreme: bool = True) -> tuple[int, int, np.ndarray, np.ndarray] | None:
    """``(i0, j0, zlo, zhi)``: the hull of the centres of a set whose columns' lowest and highest
    reachable indices are ``kbot``, ``ktop`` (``-1`` for an empty column; at least one column set)
    meets column ``(i0 + i, j0 + j)`` in ``zlo[i, j] <= z <= zhi[i, j]`` (index units; ``zlo > zhi``
    off its footprint, and every column outside the rectangle of ``zlo`` is off it); ``None`` when
    the centres are coplanar (no 3-D hull). ``raster`` and ``extreme`` are :func:`hull_mask`'s."""
    return PendingHull(kbot, ktop, raster, extreme).result()


class PendingHull:
    """:func:`hull_limits` in two halves, so that qhull (which releases the GIL) can run beside the
    caller's other work: the constructor takes the points (a compiled kernel, in the calling thread)
    and, with ``background``, starts qhull in a thread of its own; :meth:`result` waits for it and
    rasterises its triangles (in the calling thread: the compiled kernels stay in one thread, under
    :data:`kinematics.parallel.KERNEL_LOCK`). The same limits either way."""

    def __init__(self, kbot: np.ndarray, ktop: np.ndarray, raster: bool = True, extreme: bool = True,
                 background: bool = False) -> None:
        self.raster = raster
        col = ktop >= 0
        ii, jj = np.nonzero(col)
        # the hull's footprint lies within the occupied columns' bounding rectangle
        self.rect = int(ii.min()), int(ii.max()) + 1, int(jj.min()), int(jj.max()) + 1
        self.pts = hull_points(kbot, ktop, extreme)
        self._hull: ConvexHull | None = None
        self._error: Exception | None = None
        self._thread: threading.Thread | None = None
        # the extreme points span the same affine hull as all the column ends
        self.flat = len(self.pts) < 4 or np.linalg.matrix_rank(self.pts - self.pts.mean(axis=0), tol=1e-9) < 3
        if self.flat:
            return
        if background:
            self._thread = threading.Thread(target=self._qhull, name="qhull", daemon=True)
            self._thread.start()
        else:
            self._qhull()

    def _qhull(self) -> None:
        try:  # joggled for the raster (module docstring), exact for the reference
            self._hull = ConvexHull(self.pts, qhull_options=QHULL_RASTER) if self.raster else ConvexHull(self.pts)
        except QhullError:  # pragma: no cover - lattice points of rank 3 always have a hull
            self._hull = None
        except Exception as exc:  # pragma: no cover - handed to the caller by result()
            self._error = exc

    def result(self) -> tuple[int, int, np.ndarray, np.ndarray] | None:
        """:func:`hull_limits`'s value (waits for qhull)."""
        if self._thread is not None:
            self._thread.join()
            self._thread = None
        if self._error is not None:  # pragma: no cover - qhull failed otherwise than QhullError
            raise self._error
        hull = self._hull
        if self.flat or hull is None:
            return None
        pts = self.pts
        i0, i1, j0, j1 = self.rect
        if self.raster:
            zlo = np.empty((i1 - i0, j1 - j0))
            zhi = np.empty((i1 - i0, j1 - j0))
            with KERNEL_LOCK:
                _raster_kernel(pts, hull.simplices.astype(np.int64), np.ascontiguousarray(hull.equations[:, 2]),
                               float(i0), float(j0), zlo, zhi)
        else:
            # coplanar triangles of one facet share an equation: keep one (about halves the planes)
            eq = hull.equations
            _, first = np.unique(np.round(eq, 9), axis=0, return_index=True)
            sub = np.ascontiguousarray(eq[np.sort(first)])
            sub[:, 3] += sub[:, 0] * i0 + sub[:, 1] * j0  # shift to sub-rectangle indices
            zlo, zhi = hull_columns(i1 - i0, j1 - j0, sub, 1e-7)
        return i0, j0, zlo, zhi


@njit(cache=True, nogil=True)
def _raster_kernel(pts, simplices, normal_z, i0, j0, zlo, zhi):
    """Per column ``(i, j)`` (of the rectangle from ``(i0, j0)``) the z-interval ``[zlo, zhi]`` inside
    the hull whose triangles are ``pts[simplices]`` (qhull's, outward normal z ``normal_z``): each
    triangle not vertical sets, at every column centre its projection covers (edges included), the
    height of its plane as ``zhi`` (normal up) or ``zlo`` (normal down); a column no triangle covers
    is outside the footprint (``zlo > zhi``). The points are lattice points, so the projected
    triangles' edge tests and the plane's normal are exact integers and its height the quotient of
    two (exact where the column's top lies on a lattice point)."""
    ni, nj = zlo.shape
    for a in range(ni):
        for b in range(nj):
            zlo[a, b] = np.inf
            zhi[a, b] = -np.inf
    for f in range(simplices.shape[0]):
        p0 = simplices[f, 0]
        p1 = simplices[f, 1]
        p2 = simplices[f, 2]
        x0, y0, z0 = pts[p0, 0] - i0, pts[p0, 1] - j0, pts[p0, 2]
        x1, y1, z1 = pts[p1, 0] - i0, pts[p1, 1] - j0, pts[p1, 2]
        x2, y2, z2 = pts[p2, 0] - i0, pts[p2, 1] - j0, pts[p2, 2]
        ux, uy, uz = x1 - x0, y1 - y0, z1 - z0
        vx, vy, vz = x2 - x0, y2 - y0, z2 - z0
        nx_ = uy * vz - uz * vy
        ny_ = uz * vx - ux * vz
        nz_ = ux * vy - uy * vx
        if nz_ == 0.0:  # vertical: its projection is a segment, covered by its neighbours'
            continue
        if nz_ < 0.0:  # counter-clockwise in projection
            x1, y1, x2, y2 = x2, y2, x1, y1
            nx_, ny_, nz_ = -nx_, -ny_, -nz_
        upper = normal_z[f] > 0.0
        ia = int(max(0.0, min(x0, x1, x2)))
        ib = int(min(ni - 1.0, max(x0, x1, x2)))
        ja = int(max(0.0, min(y0, y1, y2)))
        jb = int(min(nj - 1.0, max(y0, y1, y2)))
        for i in range(ia, ib + 1):
            for j in range(ja, jb + 1):
                if ((x1 - x0) * (j - y0) < (y1 - y0) * (i - x0) or (x2 - x1) * (j - y1) < (y2 - y1) * (i - x1)
                        or (x0 - x2) * (j - y2) < (y0 - y2) * (i - x2)):
                    continue
                z = z0 - (nx_ * (i - x0) + ny_ * (j - y0)) / nz_
                if upper:
                    if z > zhi[i, j]:
                        zhi[i, j] = z
                elif z < zlo[i, j]:
                    zlo[i, j] = z


@njit(parallel=True, cache=True, nogil=True)
def _hull_fill_kernel(zlo, zhi, i0, j0, out):
    """``out[i0 + i, j0 + j, k] = zlo[i, j] <= k <= zhi[i, j]``."""
    ni, nj = zlo.shape
    nz = out.shape[2]
    for i in prange(ni):
        for j in range(nj):
            a = zlo[i, j]
            b = zhi[i, j]
            for k in range(nz):
                kf = np.float64(k)
                out[i0 + i, j0 + j, k] = kf >= a and kf <= b
