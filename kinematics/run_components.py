r"""Connected components of a voxel set from its runs along z, not from a labelled grid.

Definition (that of :mod:`kinematics.measures`): the components of a set ``W`` of voxels under
6-adjacency (``connectivity=1``: voxels sharing a face) or 26-adjacency (``connectivity=3``: sharing
a face, an edge or a corner) -- the components ``scipy.ndimage.label`` finds with
``generate_binary_structure(3, connectivity)``; ``b0(W)`` is their number.

Computation. A *run* is a maximal segment ``k = s .. e`` of set voxels in one column ``(i, j)``; two
runs of one column are never adjacent (an unset voxel lies between them), and each run is connected.
Two runs of columns that differ by one step along x or y (6-adjacency; and also along both,
diagonally, for 26-adjacency) are adjacent exactly when their z ranges overlap (6) or overlap once
each is grown by one voxel (26: ``s_1 <= e_2 + 1`` and ``s_2 <= e_1 + 1``). The components of ``W``
are thus the components of the run graph: a union-find over the runs, each column merged with its
earlier neighbours ``(i, j - 1)``, ``(i - 1, j)`` (and ``(i - 1, j +- 1)`` for 26) by one sweep of
both sorted run lists. The grid is read once (in parallel, per x slice); the serial part works on
the runs, whose number grows with the surface of ``W``, not its volume.
"""

from __future__ import annotations

import numpy as np
from numba import njit, prange

from .parallel import KERNEL_LOCK

#: eight set bytes of a boolean grid read as one little-endian word
_EIGHT_SET = np.uint64(0x0101010101010101)


@njit(parallel=True, cache=True, nogil=True)
def _count_runs_kernel(occ, counts):
    """``counts[i * n1 + j + 1]``: the number of runs of column ``(i, j)`` of the grid ``occ`` (its bytes,
    0 or 1): the set voxels over an unset one, and the first when set (no branch: vector lanes)."""
    n0, n1, n2 = occ.shape
    for i in prange(n0):
        for j in range(n1):
            row = occ[i, j]
            c = np.int64(row[0]) if n2 else np.int64(0)
            for k in range(1, n2):
                c += row[k] > row[k - 1]
            counts[i * n1 + j + 1] = c


@njit(cache=True, forceinline=True)
def _eight(row, k):
    """The bytes ``row[k] .. row[k + 7]`` as one word (little-endian)."""
    x = np.uint64(0)
    for b in range(8):
        x |= np.uint64(row[k + b]) << np.uint64(8 * b)
    return x


@njit(parallel=True, cache=True, nogil=True)
def _fill_runs_kernel(occ, offs, rs, re):
    """``rs[q]``, ``re[q]``: first and last z of run ``q``; column ``(i, j)`` holds the runs
    ``offs[i * n1 + j] .. offs[i * n1 + j + 1] - 1``, in increasing z (``occ`` the grid's bytes, 0 or
    1). A column without runs is not read, and eight bytes that all equal the last one are passed
    over as one word."""
    n0, n1, n2 = occ.shape
    for i in prange(n0):
        for j in range(n1):
            q = offs[i * n1 + j]
            if offs[i * n1 + j + 1] == q:
                continue
            row = occ[i, j]
            prev = False
            k = 0
            while k < n2:
                if k + 8 <= n2 and _eight(row, k) == (_EIGHT_SET if prev else np.uint64(0)):
                    k += 8
                    continue
                e = min(k + 8, n2)
                while k < e:
                    v = row[k] != 0
                    if v and not prev:
                        rs[q] = k
                    elif prev and not v:
                        re[q] = k - 1
                        q += 1
                    prev = v
                    k += 1
            if prev:
                re[q] = n2 - 1


@njit(cache=True, forceinline=True)
def _find(parent, p):
    while parent[p] != p:
        parent[p] = parent[parent[p]]
        p = parent[p]
    return p


@njit(cache=True, nogil=True)
def _union_runs_kernel(offs, rs, re, n0, n1, full, parent):
    """Union-find over the runs: ``parent`` (every run its own root on entry) joins adjacent runs."""
    g = 1 if full else 0
    for i in range(n0):
        for j in range(n1):
            a0 = offs[i * n1 + j]
            a1 = offs[i * n1 + j + 1]
            if a0 == a1:
                continue
            for nb in range(4):
                if nb >= 2 and not full:
                    break
                if nb == 0:
                    ii, jj = i, j - 1
                elif nb == 1:
                    ii, jj = i - 1, j
                elif nb == 2:
                    ii, jj = i - 1, j - 1
                else:
                    ii, jj = i - 1, j + 1
                if ii < 0 or jj < 0 or jj >= n1:
                    continue
                b0 = offs[ii * n1 + jj]
                b1 = offs[ii * n1 + jj + 1]
                p = a0
                q = b0
                while p < a1 and q < b1:
                    if rs[p] <= re[q] + g and rs[q] <= re[p] + g:
                        x = _find(parent, p)
                        y = _find(parent, q)
                        if x != y:
                            if x < y:
                                parent[y] = x
                            else:
                                parent[x] = y
                    # the run that ends first meets no later run of the other column (runs of a
                    # column are at least two apart: start >= previous end + 2 > its end + g)
                    if re[p] < re[q]:
                        p += 1
                    else:
                        q += 1


@njit(cache=True, nogil=True)
def _root_sizes_kernel(rs, re, parent, root, size):
    """``root[q]``: the root of run ``q``; ``size[r]``: the voxels of the component of root ``r``."""
    for q in range(rs.shape[0]):
        r = _find(parent, q)
        root[q] = r
        size[r] += re[q] - rs[q] + 1


@njit(parallel=True, cache=True, nogil=True)
def _paint_runs_kernel(offs, rs, re, keep_run, n1, out):
    """``out``: the voxels of the runs with ``keep_run`` set (``out`` all False on entry)."""
    n0 = out.shape[0]
    for i in prange(n0):
        for j in range(n1):
            for q in range(offs[i * n1 + j], offs[i * n1 + j + 1]):
                if keep_run[q]:
                    for k in range(rs[q], re[q] + 1):
                        out[i, j, k] = True


def grid_runs(occ: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The runs ``(offs, rs, re)`` along z of the boolean grid ``occ`` (C-contiguous), as
    :attr:`RunComponents.runs`."""
    n0, n1, _ = occ.shape
    offs = np.zeros(n0 * n1 + 1, np.int64)
    occ = np.ascontiguousarray(occ, dtype=np.bool_).view(np.uint8)  # the kernels read the bytes (0 or 1)
    with KERNEL_LOCK:
        if occ.size:
            _count_runs_kernel(occ, offs)
        np.cumsum(offs, out=offs)
        n_runs = int(offs[-1])
        rs = np.empty(n_runs, np.int64)
        re = np.empty(n_runs, np.int64)
        if n_runs:
            _fill_runs_kernel(occ, offs, rs, re)
    return offs, rs, re


class RunComponents:
    """The components of ``occupancy`` (module docstring): ``sizes`` (voxels per component, in no
    particular order; ``len(sizes)`` is ``b0``) and :meth:`mask` (the union of chosen components)."""

    def __init__(self, occupancy: np.ndarray, connectivity: int = 1) -> None:
        if connectivity not in (1, 3):
            raise ValueError(f"connectivity = {connectivity!r} is invalid: valid values 1 or 3")
        occ = np.ascontiguousarray(occupancy, dtype=np.bool_)
        if occ.ndim != 3:
            raise ValueError(f"occupancy has {occ.ndim} dimensions: valid values 3")
        self._join(*grid_runs(occ), occ.shape, connectivity)

    @classmethod
    def of_runs(cls, runs: tuple[np.ndarray, np.ndarray, np.ndarray], shape: tuple[int, int, int],
                connectivity: int = 1) -> RunComponents:
        """The components of the set of a grid of ``shape`` given by its runs ``(offs, rs, re)`` (as
        :attr:`runs`), without the grid."""
        if connectivity not in (1, 3):
            raise ValueError(f"connectivity = {connectivity!r} is invalid: valid values 1 or 3")
        self = cls.__new__(cls)
        self._join(*runs, tuple(int(n) for n in shape), connectivity)
        return self

    def _join(self, offs: np.ndarray, rs: np.ndarray, re: np.ndarray, shape: tuple, connectivity: int) -> None:
        """The components of the runs ``(offs, rs, re)`` of a grid of ``shape``."""
        self.shape = shape
        n0, n1, _ = shape
        n_runs = len(rs)
        with KERNEL_LOCK:
            parent = np.arange(n_runs, dtype=np.int64)
            _union_runs_kernel(offs, rs, re, n0, n1, connectivity == 3, parent)
            root = np.empty(n_runs, np.int64)
            size = np.zeros(n_runs, np.int64)
            _root_sizes_kernel(rs, re, parent, root, size)
        is_root = root == np.arange(n_runs)
        self._offs, self._rs, self._re, self._root = offs, rs, re, root
        self._roots = np.nonzero(is_root)[0]
        #: voxels of each component (``len(sizes)`` components)
        self.sizes = size[self._roots]

    def euler_characteristic(self, connectivity: int = 1) -> int:
        """:func:`kinematics.euler.euler_characteristic` of the set, from its runs (the same integer;
        :func:`kinematics.euler.euler_characteristic_of_runs`)."""
        from .euler import euler_characteristic_of_runs

        return euler_characteristic_of_runs(self._offs, self._rs, self._re, self.shape, connectivity)

    @property
    def runs(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``(offs, rs, re)``: column ``(i, j)`` holds the runs ``offs[i n1 + j] .. offs[i n1 + j + 1]
        - 1``, run ``q`` from ``rs[q]`` to ``re[q]`` (inclusive), in increasing z."""
        return self._offs, self._rs, self._re

    @property
    def count(self) -> int:
        """``b0``: the number of components."""
        return int(len(self.sizes))

    def grid(self) -> np.ndarray:
        """The whole set as a boolean grid (every run painted)."""
        return self.mask(np.ones(self.count, np.bool_))

    def mask(self, keep: np.ndarray) -> np.ndarray:
        """The voxels of the components ``c`` with ``keep[c]`` (``keep`` indexed like ``sizes``)."""
        keep_root = np.zeros(len(self._root), np.bool_)
        keep_root[self._roots] = np.asarray(keep, dtype=np.bool_)
        keep_run = keep_root[self._root]
        out = np.zeros(self.shape, np.bool_)
        with KERNEL_LOCK:
            _paint_runs_kernel(self._offs, self._rs, self._re, keep_run, self.shape[1], out)
        return out


class LabelledComponents:
    """:class:`RunComponents` by ``scipy.ndimage.label`` of the whole grid: the definition, and the
    path the measures took before the runs (the tests' reference and the benchmarks' baseline)."""

    def __init__(self, occupancy: np.ndarray, connectivity: int = 1) -> None:
        from scipy import ndimage as ndi

        occ = np.asarray(occupancy, dtype=bool)
        self.shape = occ.shape
        self._lab, self.count = ndi.label(occ, structure=ndi.generate_binary_structure(3, connectivity))
        self.sizes = np.bincount(self._lab.ravel(), minlength=1)[1:]

    @classmethod
    def of_runs(cls, runs: tuple[np.ndarray, np.ndarray, np.ndarray], shape: tuple[int, int, int],
                connectivity: int = 1) -> LabelledComponents:
        """:meth:`RunComponents.of_runs`: the grid painted from the runs, then labelled."""
        return cls(RunComponents.of_runs(runs, shape, connectivity).grid(), connectivity)

    def grid(self) -> np.ndarray:
        """The whole set as a boolean grid."""
        return self._lab > 0

    def mask(self, keep: np.ndarray) -> np.ndarray:
        """The union of the components ``keep`` (bool per component) selects."""
        return np.concatenate([[False], keep])[self._lab]

    #: No runs along z: the callers that take them (the voids' candidates) read the grid instead.
    runs = None

    def euler_characteristic(self, connectivity: int = 1) -> int:
        """``skimage.measure.euler_number`` of the set (the definition of
        :meth:`RunComponents.euler_characteristic`)."""
        from skimage.measure import euler_number

        return int(euler_number(self._lab > 0, connectivity=connectivity))


def count_components(occupancy: np.ndarray, connectivity: int = 1) -> int:
    """``b0``: ``scipy.ndimage.label(occupancy, generate_binary_structure(3, connectivity))[1]``."""
    return RunComponents(occupancy, connectivity).count
