r"""Dilation by a digital Euclidean ball, and the feature filter (an opening then a closing) built on it.

Definition. With ``B_r = {d in Z^3 : |d| <= r}`` (``r`` in voxels), the dilation of a voxel set
``X`` is ``X (+) B_r = {v : |v - u| <= r for some u in X}`` and its erosion is ``X (-) B_r =
~((~X) (+) B_r)`` (the complement's dilation, complemented); voxels outside the array are not in
``X``. The opening is ``O_r(X) = (X (-) B_r) (+) B_r`` (it drops parts thinner than about ``2 r``),
the closing ``C_r(X) = (X (+) B_r) (-) B_r`` (it fills gaps narrower than about ``2 r``), and the
feature filter of :mod:`kinematics.measures` is

    S_r(W) = C_r(O_r(W))

on the grid padded with ``floor(r) + 1`` empty voxels (the box is no obstacle to either step).

Computation (:func:`_dilate_packed_kernel`; exact, tested against ``scipy.ndimage`` and against the
distance-based :func:`ball_dilate_reference`): the set is packed 64 voxels to a word along z, and
the ball is the union over its ``(di, dj)`` offsets of the z runs ``|dk| <= floor(sqrt(r^2 - di^2 -
dj^2))``; each plane of the set, dilated along z by each run length (by shifts of whole words),
is moved by the offsets of each section ``di`` of the ball and or-ed into one row, which is or-ed
into the result's planes ``i - di`` and ``i + di`` (the sections of ``di`` and ``-di`` are the same).
The words are laid out ``[i, q, j]`` (the word index ``q`` along z before
``j``), so that every loop of the dilation runs over ``j`` on a contiguous row of words, without a
branch: the compiler puts it in vector lanes (at h = 1 a dilation took 16 ms in the ``[i, j, q]``
layout, whose inner loop was the 3 words of a z column, and 5 ms in this one). A set symmetric
under ``j -> n_y - 1 - j`` is computed on half its rows. The filter packs the set once for its
four dilations, padding it in the same parallel pass, tells whether it is mirror-symmetric from
the packed words (64 voxels per comparison), and unpacks the result without its padding: no serial
pass over the grid (no ``np.pad``, no ``np.array_equal`` for the mirror test). An erosion is the
dilation of the complemented words, complemented; the dilation reads and writes them so in its
own pass. Each dilation is one parallel region (:func:`_dilate_packed_kernel`).
"""

from __future__ import annotations

import math
from typing import Any

import numba
import numpy as np
from numba import njit, prange

from .parallel import KERNEL_LOCK
from .progress import CancelToken, check
from .run_components import grid_runs


@njit(parallel=True, cache=True, nogil=True)
def _ball_dilate_kernel(m, w, r2, d1, d2, out):
    """``out = {v : min_{u in m} |u - v|^2 <= r2}`` (index units), separably: the squared distance to
    the nearest set voxel within the window ``|du_a| <= w`` along x, then y, then z (min-plus of
    squared distances is separable); exact when ``w >= sqrt(r2)``. Each search runs outward from
    the voxel and stops once the offset alone costs more than the best found (exact)."""
    nx, ny, nz = m.shape
    big = np.int32(1 << 30)
    for i in prange(nx):
        for j in range(ny):
            for k in range(nz):
                best = big
                for di in range(w + 1):
                    if (i + di < nx and m[i + di, j, k]) or (i - di >= 0 and m[i - di, j, k]):
                        best = di * di
                        break
                d1[i, j, k] = best
    for i in prange(nx):
        for j in range(ny):
            for k in range(nz):
                best = d1[i, j, k]
                for dj in range(1, w + 1):
                    c = dj * dj
                    if c >= best:
                        break
                    if j + dj < ny and d1[i, j + dj, k] + c < best:
                        best = d1[i, j + dj, k] + c
                    if j - dj >= 0 and d1[i, j - dj, k] + c < best:
                        best = d1[i, j - dj, k] + c
                d2[i, j, k] = best
    for i in prange(nx):
        for j in range(ny):
            for k in range(nz):
                best = d2[i, j, k]
                for dk in range(1, w + 1):
                    c = dk * dk
                    if c >= best or c > r2:
                        break
                    if k + dk < nz and d2[i, j, k + dk] + c < best:
                        best = d2[i, j, k + dk] + c
                    if k - dk >= 0 and d2[i, j, k - dk] + c < best:
                        best = d2[i, j, k - dk] + c
                out[i, j, k] = best <= r2


@njit(parallel=True, cache=True, nogil=True)
def _pack_kernel(m, p, P):
    """``P[i, q, j]``: bit ``t`` is voxel ``(i - p, j - p, 64 q + t - p)`` of ``m`` (``m`` padded with
    ``p`` empty voxels on every side, in the same pass; the bits past the padded ``nz`` are 0). The
    word index comes before ``j`` so that each ``(i, q)`` is a contiguous row over ``j``, the
    direction the dilation's loops run in (vector lanes). Each z column is read once, in order."""
    nx, ny, nz = m.shape
    NX, nw, NY = P.shape
    zero = np.uint64(0)
    for I in prange(NX):
        i = I - p
        for J in range(NY):
            j = J - p
            if not (0 <= i < nx and 0 <= j < ny):
                for q in range(nw):
                    P[I, q, J] = zero
                continue
            row = m[i, j]
            for q in range(nw):
                word = zero
                for k in range(max(64 * q - p, 0), min(64 * q + 64 - p, nz)):
                    word |= np.uint64(row[k]) << np.uint64(k + p - 64 * q)
                P[I, q, J] = word


@njit(parallel=True, cache=True, nogil=True)
def _pack_runs_kernel(offs, rs, re, n0, n1, p, P):
    """:func:`_pack_kernel`'s ``P`` from the set's runs along z (column ``(i, j)`` holds the runs
    ``offs[i n1 + j] .. offs[i n1 + j + 1] - 1``, from ``rs`` to ``re``; those of
    :class:`kinematics.run_components.RunComponents`): each run sets the bits of its voxels, a
    word's range at a time, so the work grows with the runs, not with the voxels."""
    NX, nw, NY = P.shape
    zero = np.uint64(0)
    ones = ~zero
    for I in prange(NX):
        for q in range(nw):
            Pq = P[I, q]
            for J in range(NY):
                Pq[J] = zero
        i = I - p
        if i < 0 or i >= n0:
            continue
        for j in range(n1):
            c = i * n1 + j
            for r in range(offs[c], offs[c + 1]):
                a = rs[r] + p
                b = re[r] + p
                for q in range(a >> 6, (b >> 6) + 1):
                    lo = max(a - 64 * q, 0)
                    hi = min(b - 64 * q, 63)
                    word = ones >> np.uint64(63 - hi + lo)  # hi - lo + 1 ones
                    P[I, q, j + p] |= word << np.uint64(lo)


@njit(parallel=True, cache=True, nogil=True)
def _unpack_kernel(P, p, out):
    """The inverse of :func:`_pack_kernel`: ``out`` is the packed set less its padding ``p`` (each
    word's bits written to its part of the z column, in order)."""
    nx, ny, nz = out.shape
    nw = P.shape[1]
    one = np.uint64(1)
    zero = np.uint64(0)
    for i in prange(nx):
        for j in range(ny):
            orow = out[i, j]
            for q in range(nw):
                word = P[i + p, q, j + p]
                for k in range(max(64 * q - p, 0), min(64 * q + 64 - p, nz)):
                    orow[k] = ((word >> np.uint64(k + p - 64 * q)) & one) != zero


@njit(cache=True, forceinline=True)
def _popcount(x):
    """The number of set bits of the word ``x`` (SWAR)."""
    x = x - ((x >> np.uint64(1)) & np.uint64(0x5555555555555555))
    x = (x & np.uint64(0x3333333333333333)) + ((x >> np.uint64(2)) & np.uint64(0x3333333333333333))
    x = (x + (x >> np.uint64(4))) & np.uint64(0x0F0F0F0F0F0F0F0F)
    return int((x * np.uint64(0x0101010101010101)) >> np.uint64(56))


@njit(cache=True, forceinline=True)
def _low_bit(x):
    """The index of the lowest set bit of the word ``x`` (not 0): its power of two is exact in a
    float, whose exponent is the index."""
    b = x & (~x + np.uint64(1))
    return math.frexp(float(b))[1] - 1


@njit(cache=True, forceinline=True)
def _inside_bits(q, lo, hi):
    """The bits of word ``q`` whose padded z ``64 q + t`` lies in ``[lo, hi)``."""
    a = max(lo - 64 * q, 0)
    b = min(hi - 64 * q, 64)
    if b <= a:
        return np.uint64(0)
    return (~np.uint64(0) >> np.uint64(64 - (b - a))) << np.uint64(a)


@njit(parallel=True, cache=True, nogil=True)
def _packed_count_runs_kernel(P, p, n0, n1, nz, counts):
    """:func:`kinematics.run_components._count_runs_kernel` of the packed set less its padding ``p``
    (``counts[i n1 + j + 1]``: the runs of column ``(i, j)``), from the words: a run starts at a set
    bit whose bit below (the word before's top bit for bit 0) is clear."""
    nw = P.shape[1]
    one, top = np.uint64(1), np.uint64(63)
    for i in prange(n0):
        for j in range(n1):
            c = 0
            below = np.uint64(0)
            for q in range(nw):
                w = P[i + p, q, j + p] & _inside_bits(q, p, p + nz)
                c += _popcount(w & ~((w << one) | below))
                below = w >> top
            counts[i * n1 + j + 1] = c


@njit(parallel=True, cache=True, nogil=True)
def _packed_fill_runs_kernel(P, p, n0, n1, nz, offs, rs, re):
    """:func:`kinematics.run_components._fill_runs_kernel` of the packed set less its padding ``p``:
    the runs' first and last z from each word's starts (a set bit over a clear one) and ends (a set
    bit under a clear one), lowest first; starts and ends alternate along a column."""
    nw = P.shape[1]
    one, top = np.uint64(1), np.uint64(63)
    zero = np.uint64(0)
    for i in prange(n0):
        for j in range(n1):
            a = offs[i * n1 + j]
            b = a
            below = zero
            w = P[i + p, 0, j + p] & _inside_bits(0, p, p + nz)
            for q in range(nw):
                above = zero
                if q + 1 < nw:
                    nxt = P[i + p, q + 1, j + p] & _inside_bits(q + 1, p, p + nz)
                    above = (nxt & one) << top
                else:
                    nxt = zero
                starts = w & ~((w << one) | below)
                ends = w & ~((w >> one) | above)
                while starts != zero:
                    rs[a] = 64 * q + _low_bit(starts) - p
                    starts &= starts - one
                    a += 1
                while ends != zero:
                    re[b] = 64 * q + _low_bit(ends) - p
                    ends &= ends - one
                    b += 1
                below = w >> top
                w = nxt


@njit(parallel=True, cache=True, nogil=True)
def _packed_mirror_kernel(P):
    """Whether the packed set equals its image under ``j -> NY - 1 - j`` (compared word by word; the
    padding is symmetric, so the padded set is symmetric exactly when the set is)."""
    nx, nw, ny = P.shape
    diff = np.zeros(nx, np.bool_)
    for i in prange(nx):
        for q in range(nw):
            row = P[i, q]
            for j in range(ny // 2):
                if row[j] != row[ny - 1 - j]:
                    diff[i] = True
                    break
            if diff[i]:
                break
    return not diff.any()


@njit(parallel=True, cache=True, nogil=True)
def _mirror_kernel(m):
    """Whether ``m`` equals ``m[:, ::-1]`` (x slices in parallel; each slice stops at its first
    difference)."""
    nx, ny, nz = m.shape
    diff = np.zeros(nx, np.bool_)
    for i in prange(nx):
        for j in range(ny // 2):
            jj = ny - 1 - j
            for k in range(nz):
                if m[i, j, k] != m[i, jj, k]:
                    diff[i] = True
                    break
            if diff[i]:
                break
    return not diff.any()


def is_mirror_symmetric(mask: np.ndarray) -> bool:
    """``np.array_equal(mask, mask[:, ::-1])`` by :func:`_mirror_kernel` (a parallel pass)."""
    m = np.ascontiguousarray(mask, dtype=np.bool_)
    if m.ndim != 3 or m.size == 0:
        return bool(np.array_equal(m, m[:, ::-1]))
    with KERNEL_LOCK:
        return bool(_mirror_kernel(m))


@njit(cache=True, forceinline=True)
def _valid_bits(q, nw, last):
    """The valid bits of word ``q`` of a row of ``nw`` words (``last``: those of the last word)."""
    return last if q == nw - 1 else ~np.uint64(0)


@njit(parallel=True, cache=True, nogil=True)
def _dilate_packed_kernel(P, DI, DJ, A, w, half, last, flip, n_slab, R):
    """``R``: the packed set ``P`` dilated by the ball whose offsets ``(DI[e], DJ[e])`` carry the z
    runs ``|dk| <= A[e]`` (:func:`_ball_offsets`), by sections: the ball is the union over ``di`` of
    its sections ``{(dj, dk) : (di, dj, dk) in B_r}``, and the section of ``di`` is that of ``-di``.
    So each plane ``p`` of ``P`` is dilated along z by ``[-a, a]`` for ``a = 0 .. w`` (``Z[a]``, that of
    ``a - 1`` or-ed with the plane moved ``a`` bits each way across the words), then by each section
    ``d = 0 .. w`` (``S``: ``Z[A[e]]`` moved by ``DJ[e]`` along y, or-ed over the offsets with ``DI[e] =
    d``), and ``S`` is or-ed into ``R`` at the planes ``p - d`` and ``p + d``: about ``(m + 2 w + 1) /
    2`` row passes a plane for the ``m`` offsets of the ball, against ``m`` read-modify-writes of ``R``
    when each offset was or-ed in alone (at h = 1, radius 6.36 voxels: 84 against 129; a dilation
    0.71-0.86 of its time, 0.62-0.68 at h = 0.5). With ``half`` (``P`` symmetric under ``j -> ny - 1 -
    j``, so ``R`` is too) only the rows ``j >= ny // 2`` are or-ed, the others copied. Bits past ``nz``
    are cleared (``last``). Every inner loop runs over ``j`` on contiguous rows ``[., q, :]`` without
    a branch (vector lanes). ``flip`` (all bits set, else 0): the erosion, i.e. ``P`` read complemented
    and ``R`` written complemented (the valid bits only), in the same pass.

    One parallel region: the ``x`` planes of ``R`` are dealt in ``n_slab`` slabs (:func:`_slabs`), and
    each slab streams the planes its sections reach, its own and the ``w`` on either side (the halo,
    dilated along z twice: ``2 w`` planes a slab), with one plane's ``Z`` and one ``S`` as its work
    arrays (62 kB and 9 kB at h = 1). The result does not depend on the slabs (tested)."""
    nx, nw, ny = P.shape
    j0 = ny // 2 if half else 0
    zero = np.uint64(0)
    n = DI.shape[0]
    n_slab = max(min(nx, n_slab), 1)
    for s in prange(n_slab):
        i0 = s * nx // n_slab
        i1 = (s + 1) * nx // n_slab
        Z = np.empty((w + 1, nw, ny), np.uint64)  # plane p dilated along z by [-a, a], for each a
        S = np.empty((nw, ny), np.uint64)  # plane p dilated by the section d of the ball
        for i in range(i0, i1):
            for q in range(nw):
                Rq = R[i, q]
                for j in range(ny):
                    Rq[j] = zero
        for p in range(max(i0 - w, 0), min(i1 + w, nx)):
            for q in range(nw):
                Pq = P[p, q]
                mq = _valid_bits(q, nw, last)
                Z0 = Z[0, q]
                for j in range(ny):
                    Z0[j] = (Pq[j] ^ flip) & mq
            for a in range(1, w + 1):
                # Z[0] holds the plane's words read (complemented with flip); a word's neighbours
                # shift their bits across the boundary (Z[0, q - 1] has every bit valid)
                ua = np.uint64(a)
                ub = np.uint64(64 - a)
                for q in range(nw):
                    Za = Z[a, q]
                    Zb = Z[a - 1, q]
                    Z0 = Z[0, q]
                    if q > 0 and q + 1 < nw:
                        Zm = Z[0, q - 1]
                        Zp = Z[0, q + 1]
                        for j in range(ny):
                            v = Z0[j]
                            Za[j] = Zb[j] | (v << ua) | (v >> ua) | (Zm[j] >> ub) | (Zp[j] << ub)
                    elif q > 0:
                        Zm = Z[0, q - 1]
                        for j in range(ny):
                            v = Z0[j]
                            Za[j] = Zb[j] | (v << ua) | (v >> ua) | (Zm[j] >> ub)
                    elif q + 1 < nw:
                        Zp = Z[0, q + 1]
                        for j in range(ny):
                            v = Z0[j]
                            Za[j] = Zb[j] | (v << ua) | (v >> ua) | (Zp[j] << ub)
                    else:
                        for j in range(ny):
                            v = Z0[j]
                            Za[j] = Zb[j] | (v << ua) | (v >> ua)
            for d in range(w + 1):
                down = i0 <= p - d < i1  # the plane p - d of R takes the section di = d
                up = d > 0 and i0 <= p + d < i1  # and p + d that of di = -d
                if not (down or up):
                    continue
                a0 = 0
                for e in range(n):
                    if DI[e] == d and DJ[e] == 0:
                        a0 = A[e]
                for q in range(nw):
                    Sq = S[q]
                    Zq = Z[a0, q]
                    for j in range(j0, ny):
                        Sq[j] = Zq[j]
                for e in range(n):
                    if DI[e] != d or DJ[e] == 0:
                        continue
                    dj = DJ[e]
                    lo = max(j0, -dj)
                    hi = min(ny, ny - dj)
                    if hi <= lo:
                        continue
                    a = A[e]
                    for q in range(nw):
                        Sv = S[q, lo:hi]
                        Zv = Z[a, q, lo + dj:hi + dj]
                        for t in range(hi - lo):
                            Sv[t] |= Zv[t]
                for side in range(2):
                    if (side == 0 and down) or (side == 1 and up):
                        t = p - d if side == 0 else p + d
                        for q in range(nw):
                            Rv = R[t, q, j0:ny]
                            Sv = S[q, j0:ny]
                            for j in range(ny - j0):
                                Rv[j] |= Sv[j]
        for i in range(i0, i1):
            for q in range(nw):
                Rq = R[i, q]
                mq = _valid_bits(q, nw, last)
                for j in range(j0, ny):
                    Rq[j] = (Rq[j] ^ flip) & mq
            if half:
                for q in range(nw):
                    Rq = R[i, q]
                    for j in range(j0):
                        Rq[j] = Rq[ny - 1 - j]


def _slabs() -> int:
    """Slabs of :func:`_dilate_packed_kernel`: two per thread of the launch. Every plane costs the
    same, so any equal slabs balance the threads, and each slab's work arrays hold one plane whatever
    its size (at h = 1 on 2 threads a dilation took 5.20 ms in 2 slabs, 5.31 ms in 4 and 5.54 ms in 8,
    medians of 31 on a slow hour of the host: within its noise). Read here, not in the kernel: numba
    does not cache a kernel that reads its thread count."""
    return 2 * numba.get_num_threads()


def _ball_offsets(r2: int, w: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The digital ball ``{d in Z^3 : |d|^2 <= r2}`` as z runs: its ``(di, dj)`` offsets and each
    one's half-length ``floor(sqrt(r2 - di^2 - dj^2))`` (int64 arrays)."""
    d = np.arange(-w, w + 1)
    di, dj = (a.ravel() for a in np.meshgrid(d, d, indexing="ij"))
    rest = r2 - di * di - dj * dj
    keep = rest >= 0
    runs = np.array([math.isqrt(int(v)) for v in rest[keep]], np.int64)
    return di[keep].astype(np.int64), dj[keep].astype(np.int64), np.minimum(runs, w)


class _Packed:
    """A boolean grid padded by ``pad`` empty voxels on every side and packed along z for
    :func:`_dilate_packed_kernel` (the set's words, an array for the result and the ball's
    offsets), dilated and complemented in place of the arrays it holds; :meth:`unpack` drops the
    padding again.
    ``symmetric=None``: whether the set is mirror-symmetric is read from the packed words
    (:func:`_packed_mirror_kernel`, 64 voxels per comparison). ``runs``: the set's runs ``(offs, rs,
    re)``, when the caller holds them (packed from them, :func:`_pack_runs_kernel`: the same words)."""

    def __init__(self, m: np.ndarray, radius_voxels: float, symmetric: bool | None, pad: int = 0,
                 runs: tuple | None = None) -> None:
        m = np.ascontiguousarray(m, dtype=np.bool_)
        self.shape, self.pad = m.shape, int(pad)
        nx, ny, nz = (n + 2 * self.pad for n in m.shape)
        nw = -(-nz // 64)
        rem = nz - 64 * (nw - 1)
        self.last = np.uint64((1 << rem) - 1) if rem < 64 else np.uint64(0xFFFFFFFFFFFFFFFF)
        self.w = int(np.floor(radius_voxels + 1e-9))
        self.offsets = _ball_offsets(int(np.floor(radius_voxels * radius_voxels + 1e-9)), self.w)
        self.P = np.empty((nx, nw, ny), np.uint64)
        self.R = np.empty_like(self.P)
        with KERNEL_LOCK:
            if runs is None:
                _pack_kernel(m, self.pad, self.P)
            else:
                _pack_runs_kernel(*runs, m.shape[0], m.shape[1], self.pad, self.P)
            self.symmetric = bool(_packed_mirror_kernel(self.P)) if symmetric is None else bool(symmetric)

    def dilate(self, complement: bool = False) -> None:
        """The set becomes its dilation by the ball (its erosion with ``complement``)."""
        flip = np.uint64(0xFFFFFFFFFFFFFFFF if complement else 0)
        with KERNEL_LOCK:
            _dilate_packed_kernel(self.P, *self.offsets, self.w, self.symmetric, self.last, flip, _slabs(), self.R)
        self.P, self.R = self.R, self.P

    def unpack(self) -> np.ndarray:
        """The set, less its padding."""
        out = np.empty(self.shape, np.bool_)
        with KERNEL_LOCK:
            _unpack_kernel(self.P, self.pad, out)
        return out

    def runs(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The runs ``(offs, rs, re)`` along z of the set less its padding (as
        :attr:`kinematics.run_components.RunComponents.runs`), read from the words without unpacking
        them (:func:`_packed_count_runs_kernel`, :func:`_packed_fill_runs_kernel`)."""
        n0, n1, nz = self.shape
        offs = np.zeros(n0 * n1 + 1, np.int64)
        with KERNEL_LOCK:
            if n0 * n1 * nz:
                _packed_count_runs_kernel(self.P, self.pad, n0, n1, nz, offs)
            np.cumsum(offs, out=offs)
            rs = np.empty(int(offs[-1]), np.int64)
            re = np.empty_like(rs)
            if len(rs):
                _packed_fill_runs_kernel(self.P, self.pad, n0, n1, nz, offs, rs, re)
        return offs, rs, re


def ball_dilate(mask: np.ndarray, radius_voxels: float, *, complement: bool = False,
                symmetric: bool = False) -> np.ndarray:
    """Dilation of ``mask`` by the digital Euclidean ball ``{d in Z^3 : |d| <= radius_voxels}``.

    Exact (tested against ``scipy.ndimage``); voxels outside the array are taken as not in
    ``mask``. ``complement=True`` gives ``~ball_dilate(~mask)`` (the erosion of ``mask``; voxels
    outside the array are not in ``~mask``); ``symmetric=True`` says that ``mask`` equals
    ``mask[:, ::-1]`` (half the work). Packed along z (:func:`_dilate_packed_kernel`) for radii below
    64 voxels, by :func:`ball_dilate_reference`'s kernel above.
    """
    m = np.ascontiguousarray(mask, dtype=np.bool_)
    w = int(np.floor(radius_voxels + 1e-9))
    if w <= 0 or m.size == 0:
        return m.copy()
    r2 = int(np.floor(radius_voxels * radius_voxels + 1e-9))
    if w < 64:
        packed = _Packed(m, radius_voxels, symmetric)
        packed.dilate(complement)
        return packed.unpack()
    out = np.empty(m.shape, np.bool_)
    if complement:
        m = ~m
    d1i = np.empty(m.shape, np.int32)
    d2 = np.empty(m.shape, np.int32)
    with KERNEL_LOCK:
        _ball_dilate_kernel(m, w, r2, d1i, d2, out)
    return ~out if complement else out


def ball_dilate_reference(mask: np.ndarray, radius_voxels: float, *, complement: bool = False,
                          symmetric: bool = False) -> np.ndarray:
    """:func:`ball_dilate` with int32 distances over the whole array (the former kernel; the tests'
    reference for the packed and mirrored one). ``symmetric`` is accepted and ignored (the same
    signature as :func:`ball_dilate`)."""
    m = np.ascontiguousarray(mask, dtype=np.bool_)
    w = int(np.floor(radius_voxels + 1e-9))
    if w <= 0 or m.size == 0:
        return m.copy()
    if complement:
        return ~ball_dilate_reference(~m, radius_voxels)
    r2 = int(np.floor(radius_voxels * radius_voxels + 1e-9))
    d1 = np.empty(m.shape, np.int32)
    d2 = np.empty(m.shape, np.int32)
    out = np.empty(m.shape, np.bool_)
    with KERNEL_LOCK:
        _ball_dilate_kernel(m, w, r2, d1, d2, out)
    return out


class _Grids:
    """:class:`_Packed`'s steps on boolean grids (padded by ``np.pad``), each by ``dilate``
    (:func:`ball_dilate`'s signature)."""

    def __init__(self, m: np.ndarray, radius_voxels: float, symmetric: bool | None, pad: int, dilate) -> None:
        self.o, self.pad = np.pad(np.asarray(m, dtype=bool), pad), pad
        self.symmetric = is_mirror_symmetric(self.o) if symmetric is None else symmetric
        self.r, self._dilate = radius_voxels, dilate

    def dilate(self, complement: bool = False) -> None:
        self.o = self._dilate(self.o, self.r, complement=complement, symmetric=self.symmetric)

    def unpack(self) -> np.ndarray:
        p = self.pad
        return self.o[p:-p, p:-p, p:-p]

    def runs(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        return grid_runs(np.ascontiguousarray(self.unpack()))


def _open_close(occupancy: np.ndarray, radius_voxels: float, cancel: CancelToken, grids,
                as_runs: bool = False) -> Any:
    """:func:`feature_filter`'s steps on the solid padded by ``floor(r) + 1`` empty voxels, held by
    ``grids(occupancy, r, symmetric, pad)`` (a :class:`_Packed` or a :class:`_Grids`; ``symmetric=None``:
    each finds whether the solid equals its mirror image ``j -> n_y - 1 - j``, the packed one on its
    words); ``as_runs``: the result as its runs along z (``grids``' ``runs()``), not as a grid."""
    occ = np.asarray(occupancy, dtype=bool)
    w = int(np.floor(radius_voxels + 1e-9))
    if w <= 0:
        return grid_runs(np.ascontiguousarray(occ)) if as_runs else occ.copy()
    g = grids(occ, radius_voxels, None, w + 1)  # symmetric or not, found by the grids; each step keeps it
    for step, complement in enumerate((True, False, False, True)):  # erode, dilate: open; dilate, erode: close
        if step:
            check(cancel)
        g.dilate(complement)
    return g.runs() if as_runs else g.unpack()


def feature_filter(occupancy: np.ndarray, radius_voxels: float, cancel: CancelToken = None,
                   runs: tuple | None = None, *, as_runs: bool = False) -> Any:
    """``S_r = close_r(open_r(W))`` with the digital Euclidean ball of radius ``radius_voxels``.

    The opening drops material thinner than about ``2 r`` (knife-edged sheets, specks, thin
    bridges); the closing then fills gaps, slots and tunnels narrower than about ``2 r``. The grid
    is padded with empty voxels first (the box is no obstacle to either operation), and packed once
    along z for the four dilations (:func:`_dilate_packed_kernel`; from ``runs``, the set's runs
    ``(offs, rs, re)``, when the caller holds them: the same set). ``as_runs``: the filtered set as
    its runs along z ``(offs, rs, re)``, read from the packed words (:meth:`_Packed.runs`: no grid is
    unpacked). Raises :class:`~kinematics.progress.Cancelled` between its four dilations once
    ``cancel`` is set.
    """
    if np.floor(radius_voxels + 1e-9) >= 64:
        return feature_filter_reference(occupancy, radius_voxels, cancel, dilate=ball_dilate, as_runs=as_runs)
    return _open_close(occupancy, radius_voxels, cancel,
                       lambda m, r, sym, pad: _Packed(m, r, sym, pad, runs=runs), as_runs)


def feature_filter_reference(occupancy: np.ndarray, radius_voxels: float, cancel: CancelToken = None,
                             runs: tuple | None = None, *, dilate=ball_dilate_reference, as_runs: bool = False) -> Any:
    """:func:`feature_filter` (the same signature, so it can stand in for it; ``runs`` unused) as four dilations of
    boolean grids, each by ``dilate`` (:func:`ball_dilate`'s signature; by default
    :func:`ball_dilate_reference`: the former path the tests and the benchmarks compare with)."""
    return _open_close(occupancy, radius_voxels, cancel, lambda m, r, sym, pad: _Grids(m, r, sym, pad, dilate),
                       as_runs)
