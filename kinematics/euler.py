r"""The Euler characteristic of a voxel set, ``chi(W) = b0 - b1 + b2`` (components - tunnels + voids).

Definition (Ohser et al.; ``skimage.measure.euler_number``): every ``2 x 2 x 2`` window of voxels
that meets the grid (voxels outside it empty) has a configuration ``c`` in ``0 .. 255``, and

    chi(W) = (1/8) sum_windows coef[c],

with skimage's coefficients for 26-adjacency (``EULER_COEFS3D_26``), reversed (the configuration of
the complement) for 6-adjacency. The empty configuration's coefficient is 0, so windows that hold no
voxel of ``W`` add nothing.

Computation (:func:`_euler_sum_kernel`): one parallel pass that sums the coefficients per x
slice; along z each window's configuration is its near layer's four voxels (the window before's far
layer) and four new ones, and only the windows that meet the span of their four columns are read
(the same integer as skimage, tested).
"""

from __future__ import annotations

import numpy as np
from numba import njit, prange
from skimage.measure._regionprops_utils import EULER_COEFS3D_26 as _EULER_COEFS3D_26

from .parallel import KERNEL_LOCK

#: skimage's Ohser coefficients of the 256 2x2x2 configurations (26-adjacency; reversed for 6)
_EULER_26 = np.asarray(_EULER_COEFS3D_26, dtype=np.int64)


@njit(parallel=True, cache=True, nogil=True)
def _euler_sum_kernel(occ, coefs, sums):
    """``sums[i]``: ``sum coefs[c]`` over the 2x2x2 windows of low corner x index ``i - 1``, over
    every window that meets the grid (voxels outside it empty); bits as skimage's convolution gives
    them (``1`` the window's far corner, ``128`` its low corner: voxel ``(a, b, e)`` of the window is
    bit ``4 (1 - a) + (1 - b) + 2 (1 - e)``). A window's configuration is its near layer's four bits
    moved up by 2 and its far layer's four, ``c(k) = 4 f(k) + f(k + 1)`` with ``f(z)`` the four
    columns' voxels at height ``z`` (bits 32, 16, 2, 1), so each column of windows is two loops
    without a branch or a carried dependence: the layers ``f``, then the coefficients summed (no
    histogram, whose repeated bins inside the solid serialise on one memory word). Only the windows
    that meet the span of their four columns (from the lowest to the highest set voxel of any of
    them) are read: the others hold no set voxel and are counted with ``coefs[0]`` without a read."""
    n0, n1, n2 = occ.shape
    kb = np.empty((n0, n1), np.int64)  # lowest set z of each column (n2: none)
    kt = np.empty((n0, n1), np.int64)  # highest (-1: none)
    for i in prange(n0):
        for j in range(n1):
            row = occ[i, j]
            lo = n2
            hi = -1
            for k in range(n2):  # no branch: vector lanes
                o = row[k]
                lo = min(lo, k if o else n2)
                hi = max(hi, k if o else -1)
            kb[i, j] = lo
            kt[i, j] = hi
    empty = np.zeros(n2, np.bool_)
    for ii in prange(n0 + 1):
        i = ii - 1
        x0 = i >= 0
        x1 = i + 1 < n0
        f = np.zeros(n2 + 2, np.int64)
        s = 0
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
                s += coefs[0] * (n2 + 1)
                continue
            m = hi - lo + 2  # the windows k = lo - 1 .. hi
            s += coefs[0] * (n2 + 1 - m)
            r00 = occ[i, j] if c00 else empty
            r01 = occ[i, j + 1] if c01 else empty
            r10 = occ[i + 1, j] if c10 else empty
            r11 = occ[i + 1, j + 1] if c11 else empty
            # f[t] = f(lo - 1 + t): 0 below lo and above hi (every column empty there)
            f[0] = 0
            f[m] = 0
            for z in range(lo, hi + 1):
                f[z - lo + 1] = ((np.int64(r00[z]) << 5) | (np.int64(r01[z]) << 4) | (np.int64(r10[z]) << 1)
                                 | np.int64(r11[z]))
            for t in range(m):
                s += coefs[(f[t] << 2) | f[t + 1]]
        sums[ii] = s


def euler_characteristic(occupancy: np.ndarray, connectivity: int = 1) -> int:
    """``skimage.measure.euler_number(occupancy, connectivity)`` (3-D), the same integer, from one
    parallel pass that counts the 2x2x2 configurations (windows that miss the grid are empty, and
    the empty configuration's coefficient is 0)."""
    occ = np.ascontiguousarray(occupancy, dtype=np.bool_)
    coefs = _EULER_26[::-1] if connectivity == 1 else _EULER_26
    sums = np.zeros(occ.shape[0] + 1, np.int64)
    with KERNEL_LOCK:
        _euler_sum_kernel(occ, np.ascontiguousarray(coefs), sums)
    return int(0.125 * int(sums.sum()))


@njit(parallel=True, cache=True, nogil=True)
def _euler_runs_kernel(offs, rs, re, n0, n1, n2, coefs, sums):
    """``sums[i]``: :func:`_euler_sum_kernel`'s sum over the windows of low corner x index ``i - 1``,
    from the set's runs along z (:class:`kinematics.run_components.RunComponents`: column ``(a, b)``
    holds the runs ``offs[a n1 + b] .. offs[a n1 + b + 1] - 1``, from ``rs`` to ``re``). The layer
    ``f(z)`` of a column of windows changes only where one of its four columns' runs starts or ends:
    between two such events every window has the configuration ``5 f`` (its near and far layers
    alike), counted at once, and the window across an event ``4 f_old + f_new``; so the work grows
    with the runs (the surface), not with the voxels."""
    big = n2 + 2
    for ii in prange(n0 + 1):
        i = ii - 1
        q = np.empty(4, np.int64)
        q_end = np.empty(4, np.int64)
        inside = np.zeros(4, np.bool_)
        bit = np.array([32, 16, 2, 1], np.int64)
        s = 0
        for j in range(-1, n1):
            for c in range(4):
                a = i + c // 2
                b = j + c % 2
                inside[c] = False
                if 0 <= a < n0 and 0 <= b < n1:
                    q[c] = offs[a * n1 + b]
                    q_end[c] = offs[a * n1 + b + 1]
                else:
                    q[c] = 0
                    q_end[c] = 0
            f = 0
            z_prev = -1
            counted = 0
            while True:
                z_e = big
                for c in range(4):
                    if q[c] < q_end[c]:
                        z = re[q[c]] + 1 if inside[c] else rs[q[c]]
                        z_e = min(z_e, z)
                if z_e == big:
                    break
                g = f
                for c in range(4):
                    if q[c] < q_end[c]:
                        if inside[c]:
                            if re[q[c]] + 1 == z_e:
                                inside[c] = False
                                q[c] += 1
                                g &= ~bit[c]
                        elif rs[q[c]] == z_e:
                            inside[c] = True
                            g |= bit[c]
                n = z_e - 1 - z_prev  # the windows with both layers in [z_prev, z_e - 1]
                s += n * coefs[5 * f] + coefs[4 * f + g]
                counted += n + 1
                f = g
                z_prev = z_e
            s += (n2 + 1 - counted) * coefs[0]
        sums[ii] = s


def euler_characteristic_of_runs(offs: np.ndarray, rs: np.ndarray, re: np.ndarray, shape: tuple,
                                 connectivity: int = 1) -> int:
    """:func:`euler_characteristic` of the set whose runs along z are ``offs, rs, re`` (those of
    :class:`kinematics.run_components.RunComponents`) in a grid of ``shape``: the same integer, with
    work that grows with the runs (:func:`_euler_runs_kernel`)."""
    n0, n1, n2 = shape
    coefs = np.ascontiguousarray(_EULER_26[::-1] if connectivity == 1 else _EULER_26)
    sums = np.zeros(n0 + 1, np.int64)
    with KERNEL_LOCK:
        _euler_runs_kernel(offs, rs, re, n0, n1, n2, coefs, sums)
    return int(0.125 * int(sums.sum()))
