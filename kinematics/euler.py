r"""The Euler characteristic of a voxel set, ``chi(W) = b0 - b1 + b2`` (components - tunnels + voids).

Definition (Ohser et al.; ``skimage.measure.euler_number``): every ``2 x 2 x 2`` window of voxels
that meets the grid (voxels outside it empty) has a configuration ``c`` in ``0 .. 255``, and

    chi(W) = (1/8) sum_windows coef[c],

with skimage's coefficients for 26-adjacency (``EULER_COEFS3D_26``), reversed (the configuration of
the complement) for 6-adjacency. The empty configuration's coefficient is 0, so windows that hold no
voxel of ``W`` add nothing.

Computation (:func:`_euler_hist_kernel`): one parallel pass that counts the configurations per x
slice; along z each window reads four new voxels (the rest is the previous window's far layer), and
only the windows that meet the span of their four columns are read (the same integer as skimage,
tested).
"""

from __future__ import annotations

import numpy as np
from numba import njit, prange
from skimage.measure._regionprops_utils import EULER_COEFS3D_26 as _EULER_COEFS3D_26

from .parallel import KERNEL_LOCK

#: skimage's Ohser coefficients of the 256 2x2x2 configurations (26-adjacency; reversed for 6)
_EULER_26 = np.asarray(_EULER_COEFS3D_26, dtype=np.int64)


@njit(parallel=True, cache=True, nogil=True)
def _euler_hist_kernel(occ, hist):
    """``hist[i, c]``: 2x2x2 windows of low corner x index ``i - 1`` with configuration ``c``, over
    every window that meets the grid (voxels outside it empty); bits as skimage's convolution
    gives them (``1`` the window's far corner, ``128`` its low corner: voxel ``(a, b, e)`` of the
    window is bit ``4 (1 - a) + (1 - b) + 2 (1 - e)``). Along z each window's configuration is the
    previous one's far layer moved to the near layer (bits 0, 1, 4, 5 shifted by 2) and four new
    voxels, so each window reads four voxels; and only the windows that meet the span of their four
    columns (from the lowest to the highest set voxel of any of them) are read: the others hold no
    set voxel and are counted as configuration 0 without a read."""
    n0, n1, n2 = occ.shape
    kb = np.empty((n0, n1), np.int64)  # lowest set z of each column (n2: none)
    kt = np.empty((n0, n1), np.int64)  # highest (-1: none)
    for i in prange(n0):
        for j in range(n1):
            lo = n2
            for k in range(n2):
                if occ[i, j, k]:
                    lo = k
                    break
            hi = -1
            if lo < n2:
                for k in range(n2 - 1, lo - 1, -1):
                    if occ[i, j, k]:
                        hi = k
                        break
            kb[i, j] = lo
            kt[i, j] = hi
    for ii in prange(n0 + 1):
        i = ii - 1
        x0 = i >= 0
        x1 = i + 1 < n0
        row = np.zeros(256, np.int64)
        for j in range(-1, n1):
            y0 = j >= 0
            y1 = j + 1 < n1
            c00 = x0 and y0
            c01 = x0 and y1
            c10 = x1 and y0
            c11 = x1 and y1
            lo = n2
            hi = -1
            if c00:
                lo = min(lo, kb[i, j])
                hi = max(hi, kt[i, j])
            if c01:
                lo = min(lo, kb[i, j + 1])
                hi = max(hi, kt[i, j + 1])
            if c10:
                lo = min(lo, kb[i + 1, j])
                hi = max(hi, kt[i + 1, j])
            if c11:
                lo = min(lo, kb[i + 1, j + 1])
                hi = max(hi, kt[i + 1, j + 1])
            if hi < 0:
                row[0] += n2 + 1
                continue
            row[0] += n2 + 1 - (hi - lo + 2)  # the windows below lo - 1 and above hi
            code = 0
            for k in range(lo - 1, hi + 1):
                z = k + 1
                far = 0
                if z < n2:
                    if c00 and occ[i, j, z]:
                        far |= 32
                    if c01 and occ[i, j + 1, z]:
                        far |= 16
                    if c10 and occ[i + 1, j, z]:
                        far |= 2
                    if c11 and occ[i + 1, j + 1, z]:
                        far |= 1
                code = ((code & 0x33) << 2) | far
                row[code] += 1
        for c in range(256):
            hist[ii, c] = row[c]


def euler_characteristic(occupancy: np.ndarray, connectivity: int = 1) -> int:
    """``skimage.measure.euler_number(occupancy, connectivity)`` (3-D), the same integer, from one
    parallel pass that counts the 2x2x2 configurations (windows that miss the grid are empty, and
    the empty configuration's coefficient is 0)."""
    occ = np.ascontiguousarray(occupancy, dtype=np.bool_)
    coefs = _EULER_26[::-1] if connectivity == 1 else _EULER_26
    hist = np.zeros((occ.shape[0] + 1, 256), np.int64)
    with KERNEL_LOCK:
        _euler_hist_kernel(occ, hist)
    return int(0.125 * int(coefs @ hist.sum(axis=0)))
