"""Exact coarse-to-fine workspace engine: classify blocks of voxels, split only the undecided ones.

The dense engine (:func:`kinematics.workspace._run_grid` with ``method="dense"``) decides every
voxel centre ``P`` with the per-chain test of :mod:`kinematics.feasibility`. This engine returns
the **same voxels** (tested voxel by voxel against it) while spending its work near the surface.

Lemma (Lipschitz). For a fixed carriage pose (arc sample ``k``, rail coordinate ``rho``) each leg
length ``L_j(P) = |B_j(P) - D_j|`` with ``B_j = P + R u_j`` satisfies ``|L_j(P) - L_j(Pc)| <=
|P - Pc|``.

Let a block be a box of voxel centres with centre ``Pc`` and half-diagonal ``delta`` (so every
centre ``P`` of the block has ``|P - Pc| <= delta``), and ``e = delta + eps`` with a small
``eps`` (1e-9 of the design's scale) that absorbs floating-point rounding. For chain ``i``:

* **all fail**: if at ``Pc`` no arc sample admits a ``rho`` with both legs in the relaxed range
  ``[l_min - e, l_max + e]`` (the whole-stroke bound with relaxed limits first, then every sample),
  then no sample admits one with the exact range at any centre ``P`` of the block (the same
  ``(k, rho)`` would work at ``Pc`` relaxed, by the lemma). The dense test fails at every ``P``.
* **all succeed**: if at ``Pc`` some sample ``k`` admits a ``rho`` with both legs in the tightened
  range ``[l_min + e, l_max - e]``, then the same ``(k, rho)`` works with the exact range at every
  centre ``P``, with a margin of at least ``eps``: the dense test's sample search succeeds (and its
  conservative whole-stroke bound, which never rejects a feasible pose, does not reject it).
* otherwise the chain stays **undecided** for the block.

Joint cones (:mod:`kinematics.joints`) join both tests: the cone function ``k |B - D| - a . (B -
D)`` is ``(1 + k)``-Lipschitz in ``P`` (for a fixed carriage pose and orientation), so the cones are
relaxed / tightened by ``(1 + k) e`` exactly like the leg limits by ``e``.

A block is unreachable as soon as one chain fails everywhere; it is reachable when every chain
succeeds everywhere; otherwise it is split in eight (halving each edge of more than one voxel) and
the children inherit the chains already decided. A single voxel is decided with the dense test
itself (exact limits), so the result is voxel-identical to the dense engine for every
orientation, both arc ranges and with or without the mirror (which is applied to the computed
half exactly as the dense engine does). In diagnostics mode every chain is decided, so the
per-chain bit masks are identical too.

Cost: about the number of blocks that touch the boundary of a chain's set, i.e. it grows like the
surface (``h^-2``), not the volume (``h^-3``).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit, prange

from .feasibility import _feasible_at, chain_excluded_at, chain_points, sub_arc_excluded_at
from .parallel import KERNEL_LOCK, kernel_launch
from .progress import CancelToken, Reporter, check

__all__ = ["decide_chain", "initial_windows", "run_blocks", "rounding_margin", "sub_arcs", "TOP_BLOCK"]

#: Edge (in voxels) of the coarsest blocks.
TOP_BLOCK = 16
#: Levels of the coarse-to-fine walk from a top block down to single voxels (halving each level).
LEVELS = int(math.ceil(math.log2(TOP_BLOCK))) + 1

UNKNOWN, OK, FAIL = 0, 1, 2


@njit(cache=True, forceinline=True)
def _segment_open(b1x, b1y, b1z, b2x, b2y, b2z, hb, seg_arc, i, g, rho_lo, rho_hi, lo, hi):
    """False when the whole-arc bound rejects chain ``i`` over its sub-arc ``g`` (``seg_arc[i, g]``)
    with limits ``[lo, hi]``."""
    return not sub_arc_excluded_at(b1x, b1y, b1z, b2x, b2y, b2z, hb, seg_arc, i, g, rho_lo, rho_hi, lo * lo, hi * hi)


@njit(cache=True, forceinline=True)
def _stroke_open(b1x, b1y, b1z, b2x, b2y, b2z, hb, arc, i, rho_lo, rho_hi, lo, hi):
    """False when the whole-arc bound rejects chain ``i`` over its whole stroke (``arc[i]``) with
    limits ``[lo, hi]``."""
    return not chain_excluded_at(b1x, b1y, b1z, b2x, b2y, b2z, hb, arc, i, rho_lo, rho_hi, lo * lo, hi * hi)


@njit(cache=True, forceinline=True)
def decide_chain(px, py, pz, u, i, cos_t, sin_t, arc, seg_k, seg_arc, hb, rho_lo, rho_hi, lmin, lmax, jc,
                 e_bound, e_relax, cone_relax, e_tight, can_ok, win):
    """OK / FAIL / UNKNOWN for chain ``i`` around the point P: OK when some sample passes with the leg
    limits tightened by ``e_tight`` (cones by ``(1 + k) e_tight``); FAIL when every sample fails with
    the limits relaxed by ``e_relax`` (cones by ``cone_relax``) or lies in a sub-arc that the
    whole-arc bound rejects with the limits relaxed by ``e_bound``; UNKNOWN otherwise.

    ``win = (hint, lo, hi)`` (updated in place for the children): only the samples ``lo..hi`` are
    visited, the ``hint`` first. A caller passes the window its parent left: samples outside it
    failed the parent's relaxed test, which covers every point of the children (their points are
    the parent's), so they cannot pass. On UNKNOWN after a full visit, the window shrinks to the
    samples that passed the relaxed test and the hint to one of them; on OK the hint is the
    passing sample.

    ``cos_t, sin_t`` (3, n) are the arc samples, ``seg_k`` / ``seg_arc`` their sub-arcs
    (:func:`sub_arcs`), visited outward from the hint's. ``can_ok = False`` skips the OK test. With
    ``e_relax = e_tight = 0`` this is the exact test at P (one evaluation per sample)."""
    b1x, b1y, b1z, b2x, b2y, b2z = chain_points(px, py, pz, u, i)
    jci = jc[i]  # one view per call, not one per sample (each view costs two atomic reference counts)
    n = cos_t.shape[1]
    klo = max(win[1], 0)
    khi = min(win[2], n - 1)
    hint = win[0]
    if hint < klo or hint > khi:
        hint = (klo + khi) // 2
    lo_r = max(lmin - e_relax, 0.0)
    hi_r = lmax + e_relax
    lo_r2, hi_r2 = lo_r * lo_r, hi_r * hi_r
    lo_t = lmin + e_tight
    hi_t = lmax - e_tight
    can_ok = can_ok and lo_t <= hi_t
    lo_t2, hi_t2 = lo_t * lo_t, hi_t * hi_t
    exact = e_relax == 0.0 and e_tight == 0.0 and cone_relax == 0.0
    if klo > khi:
        return FAIL
    # the hint first: it usually serves the whole block
    if can_ok and _feasible_at(b1x, b1y, b1z, b2x, b2y, b2z, cos_t[i, hint], sin_t[i, hint], hb, rho_lo, rho_hi,
                               lo_t2, hi_t2, jci, -e_tight):
        win[0] = hint
        return OK
    lo_b = max(lmin - e_bound, 0.0)
    hi_b = lmax + e_bound
    narrow = khi - klo < seg_k[0, 1] - seg_k[0, 0]  # fewer samples than a sub-arc: no bound is worth it
    if not narrow and not _stroke_open(b1x, b1y, b1z, b2x, b2y, b2z, hb, arc, i, rho_lo, rho_hi, lo_b, hi_b):
        return FAIL
    n_seg = seg_k.shape[0]
    g_lo = 0
    while g_lo < n_seg - 1 and seg_k[g_lo, 1] < klo:
        g_lo += 1
    g_hi = n_seg - 1
    while g_hi > 0 and seg_k[g_hi, 0] > khi:
        g_hi -= 1
    first = g_lo
    while first < g_hi and seg_k[first, 1] < hint:
        first += 1
    p_lo = n
    p_hi = -1
    for step in range(2 * n_seg):
        off = (step + 1) // 2
        g = first + off if step % 2 == 1 else first - off
        if g < g_lo or g > g_hi:
            if off > n_seg:
                break
            continue
        if not narrow and not _segment_open(b1x, b1y, b1z, b2x, b2y, b2z, hb, seg_arc, i, g, rho_lo, rho_hi,
                                            lo_b, hi_b):
            continue
        for k in range(max(seg_k[g, 0], klo), min(seg_k[g, 1], khi) + 1):
            if _feasible_at(b1x, b1y, b1z, b2x, b2y, b2z, cos_t[i, k], sin_t[i, k], hb, rho_lo, rho_hi, lo_r2, hi_r2,
                            jci, cone_relax):
                if exact:
                    win[0] = k
                    return OK if can_ok else UNKNOWN
                if not can_ok:  # nothing to gain from a full visit: keep the window
                    win[0] = k
                    return UNKNOWN
                if _feasible_at(b1x, b1y, b1z, b2x, b2y, b2z, cos_t[i, k], sin_t[i, k], hb, rho_lo, rho_hi,
                                lo_t2, hi_t2, jci, -e_tight):
                    win[0] = k
                    return OK
                p_lo = min(p_lo, k)
                p_hi = max(p_hi, k)
    if p_hi >= 0:
        win[0] = min(max(hint, p_lo), p_hi)
        win[1] = p_lo
        win[2] = p_hi
        return UNKNOWN
    return FAIL


def initial_windows(nb: int, n_eta: int) -> np.ndarray:
    """Sample windows ``(hint, lo, hi)`` of :func:`decide_chain` for ``nb`` blocks: every sample,
    the middle one first. Shape (nb, 3, 3)."""
    win = np.empty((nb, 3, 3), np.int64)
    win[:, :, 0] = n_eta // 2
    win[:, :, 1] = 0
    win[:, :, 2] = n_eta - 1
    return win


def rounding_margin(lmax: float, axes: tuple[np.ndarray, ...]) -> float:
    """``eps``: 1e-9 of the design's scale (the leg length and the grid's extent), far above the
    rounding error of the tests and far below any geometric feature. The whole-arc bounds reject a
    chain only with their limits relaxed by ``eps``, so they never contradict a sample test: both
    engines then decide exactly "some arc sample passes" (:mod:`kinematics.feasibility`)."""
    return 1e-9 * max(1.0, lmax, *(float(np.abs(a).max()) for a in axes))


def sub_arcs(cos_t: np.ndarray, sin_t: np.ndarray, per: int = 12) -> tuple[np.ndarray, np.ndarray]:
    """Split each chain's arc samples into sub-arcs of ``per`` sample gaps: ``(seg_k, seg_arc)`` with
    ``seg_k[g] = (first, last)`` sample of sub-arc ``g`` (consecutive sub-arcs share their end
    sample) and ``seg_arc[i, g]`` its ``(cos v0, sin v0, cos v1, sin v1, cos vm, sin vm)`` for
    :func:`kinematics.feasibility._leg_excluded` (``vm`` the bisector)."""
    n = cos_t.shape[1]
    starts = list(range(0, max(n - 1, 1), per))
    seg_k = np.array([[k, min(k + per, n - 1)] for k in starts], np.int64)
    c0, s0 = cos_t[:, seg_k[:, 0]], sin_t[:, seg_k[:, 0]]
    c1, s1 = cos_t[:, seg_k[:, 1]], sin_t[:, seg_k[:, 1]]
    cm, sm = c0 + c1, s0 + s1
    norm = np.hypot(cm, sm)
    seg_arc = np.ascontiguousarray(np.stack([c0, s0, c1, s1, cm / norm, sm / norm], axis=2))
    return seg_k, seg_arc


@njit(cache=True, forceinline=True)
def block_centre(b0, bn, b, xs, ys, zs):
    """Centre of block ``b``'s voxel centres (its first voxel ``b0[b]``, ``bn[b]`` voxels per axis)."""
    return (0.5 * (xs[b0[b, 0]] + xs[b0[b, 0] + bn[b, 0] - 1]),
            0.5 * (ys[b0[b, 1]] + ys[b0[b, 1] + bn[b, 1] - 1]),
            0.5 * (zs[b0[b, 2]] + zs[b0[b, 2] + bn[b, 2] - 1]))


@njit(parallel=True, cache=True, nogil=True)
def _classify_kernel(b0, bn, state, win, xs, ys, zs, h, eps, all_chains,
                     u, cos_t, sin_t, arc, seg_k, seg_arc, hb, rho_lo, rho_hi, lmin, lmax, jc):
    """Decide the undecided chains of each block (in place in ``state``, shape (nb, 3)); ``win``
    (nb, 3, 3) holds each chain's sample window (:func:`decide_chain`), updated for the children."""
    for b in prange(b0.shape[0]):
        nx, ny, nz = bn[b, 0], bn[b, 1], bn[b, 2]
        px, py, pz = block_centre(b0, bn, b, xs, ys, zs)
        single = nx == 1 and ny == 1 and nz == 1
        delta = 0.5 * h * math.sqrt((nx - 1) ** 2 + (ny - 1) ** 2 + (nz - 1) ** 2)
        e = 0.0 if single else delta + eps
        for i in range(3):
            if state[b, i] != UNKNOWN:
                continue
            # the bounds reject only with one more eps of slack: they never contradict a sample test
            s = decide_chain(px, py, pz, u, i, cos_t, sin_t, arc, seg_k, seg_arc, hb, rho_lo, rho_hi,
                             lmin, lmax, jc, e + eps, e, e, e, True, win[b, i])
            state[b, i] = s
            if s == FAIL and not all_chains:
                break


@njit(cache=True, nogil=True)
def _fill_kernel(b0, bn, bits, out):
    for b in range(b0.shape[0]):
        for i in range(b0[b, 0], b0[b, 0] + bn[b, 0]):
            for j in range(b0[b, 1], b0[b, 1] + bn[b, 1]):
                for k in range(b0[b, 2], b0[b, 2] + bn[b, 2]):
                    out[i, j, k] = bits[b]


def _top_blocks(shape: tuple[int, int, int], size: int) -> tuple[np.ndarray, np.ndarray]:
    starts = [np.arange(0, n, size) for n in shape]
    gx, gy, gz = np.meshgrid(*starts, indexing="ij")
    b0 = np.stack([gx.ravel(), gy.ravel(), gz.ravel()], axis=1).astype(np.int64)
    bn = np.minimum(size, np.array(shape, np.int64)[None, :] - b0)
    return b0, bn


def _split(b0: np.ndarray, bn: np.ndarray, *inherited: np.ndarray) -> tuple[np.ndarray, ...]:
    """Eight children per block (halving every edge longer than one voxel): ``(b0, bn, *inherited)``
    with each per-block array of ``inherited`` (e.g. the chain states) repeated for the children."""
    half = (bn + 1) // 2  # first half gets the extra voxel
    kids0, kidsn = [], []
    kids: list[list[np.ndarray]] = [[] for _ in inherited]
    for dx in (0, 1):
        for dy in (0, 1):
            for dz in (0, 1):
                d = np.array([dx, dy, dz], np.int64)[None, :]
                n = np.where(d == 0, np.where(bn > 1, half, bn), bn - half)
                keep = np.all(n > 0, axis=1)
                kids0.append((b0 + d * half)[keep])
                kidsn.append(n[keep])
                for lst, arr in zip(kids, inherited):
                    lst.append(arr[keep])
    return (np.concatenate(kids0), np.concatenate(kidsn), *(np.concatenate(lst) for lst in kids))


@njit(cache=True, forceinline=True)
def n_children(bn, b):
    """Children of block ``b`` when it is split as :func:`_split` splits it: 2 per edge longer than one
    voxel (1, 2, 4 or 8)."""
    c = 1
    for a in range(3):
        if bn[b, a] > 1:
            c *= 2
    return c


@njit(cache=True, forceinline=True)
def child_offsets(counts):
    """``offs[b]``: the first row of block ``b``'s children when every block's ``counts[b]`` children
    are written consecutively in block order (``offs[-1]``: their total)."""
    offs = np.empty(counts.shape[0] + 1, np.int64)
    offs[0] = 0
    for b in range(counts.shape[0]):
        offs[b + 1] = offs[b] + counts[b]
    return offs


@njit(cache=True, forceinline=True)
def write_child(b0, bn, b, d, k0, kn, m):
    """Write child ``d`` of block ``b`` (bit ``2 - a`` of ``d``: the upper half along axis ``a``, the
    first half the larger, as :func:`_split` halves) into row ``m`` of ``k0``/``kn``; False, writing
    nothing, where it is empty (an edge of one voxel has no upper half)."""
    for a in range(3):
        if (d >> (2 - a)) & 1 and bn[b, a] == 1:
            return False
    for a in range(3):
        half = (bn[b, a] + 1) // 2
        if bn[b, a] == 1:
            k0[m, a] = b0[b, a]
            kn[m, a] = 1
        elif (d >> (2 - a)) & 1:
            k0[m, a] = b0[b, a] + half
            kn[m, a] = bn[b, a] - half
        else:
            k0[m, a] = b0[b, a]
            kn[m, a] = half
    return True


@njit(parallel=True, cache=True, nogil=True)
def _advance(b0, bn, state, win, all_chains, out, fail_bit=0):
    """One level's bookkeeping: write the bits of the decided blocks into ``out`` (the chains proven
    feasible, or'ed with ``fail_bit`` where a chain failed: the bracket's outside cubes) and return the
    undecided ones split in eight (as :func:`_split` does; each block's children consecutive, in
    block order), with the chain states and sample windows they inherit.

    Parallel over the blocks, in two passes: the first writes each decided block's voxels (the
    blocks of a level are disjoint boxes, so no two iterations write the same voxel of ``out``)
    and counts each undecided block's children; a prefix sum of the counts gives each block the
    offset of its children, which the second pass writes. The arrays returned are those of the
    serial loop (the children in the same order), for any thread count or chunking."""
    nb = b0.shape[0]
    counts = np.zeros(nb, np.int64)
    for b in prange(nb):
        unknown = False
        fail = False
        bits = 0
        for i in range(3):
            st = state[b, i]
            if st == UNKNOWN:
                unknown = True
            elif st == FAIL:
                fail = True
            else:
                bits |= 1 << i
        single = bn[b, 0] == 1 and bn[b, 1] == 1 and bn[b, 2] == 1
        if single or not unknown or (fail and not all_chains):
            if fail:
                bits |= fail_bit
            for x in range(b0[b, 0], b0[b, 0] + bn[b, 0]):
                for y in range(b0[b, 1], b0[b, 1] + bn[b, 1]):
                    for z in range(b0[b, 2], b0[b, 2] + bn[b, 2]):
                        out[x, y, z] = bits
        else:
            counts[b] = n_children(bn, b)  # >= 2: a kept block is never a single voxel
    offs = child_offsets(counts)
    n_kids = offs[nb]
    k0 = np.empty((n_kids, 3), np.int64)
    kn = np.empty((n_kids, 3), np.int64)
    ks = np.empty((n_kids, 3), np.int8)
    kw = np.empty((n_kids, 3, 3), np.int64)
    for b in prange(nb):
        if counts[b] == 0:
            continue
        m = offs[b]
        for d in range(8):
            if not write_child(b0, bn, b, d, k0, kn, m):
                continue
            for i in range(3):
                ks[m, i] = state[b, i]
                for j in range(3):
                    kw[m, i, j] = win[b, i, j]
            m += 1
    return k0, kn, ks, kw


@njit(cache=True, nogil=True)
def _advance_serial(b0, bn, state, win, all_chains, out):
    """The former serial :func:`_advance`, kept as its reference (tests, benchmark): the same arrays.

    One level's bookkeeping: write the bits of the decided blocks into ``out`` and return the
    undecided ones split in eight (as :func:`_split` does; each block's children consecutive), with the chain
    states and sample windows they inherit."""
    nb = b0.shape[0]
    keep = np.zeros(nb, np.bool_)
    n_kids = 0
    for b in range(nb):
        unknown = False
        fail = False
        bits = 0
        for i in range(3):
            st = state[b, i]
            if st == UNKNOWN:
                unknown = True
            elif st == FAIL:
                fail = True
            else:
                bits |= 1 << i
        single = bn[b, 0] == 1 and bn[b, 1] == 1 and bn[b, 2] == 1
        if single or not unknown or (fail and not all_chains):
            for x in range(b0[b, 0], b0[b, 0] + bn[b, 0]):
                for y in range(b0[b, 1], b0[b, 1] + bn[b, 1]):
                    for z in range(b0[b, 2], b0[b, 2] + bn[b, 2]):
                        out[x, y, z] = bits
        else:
            keep[b] = True
            c = 1
            for a in range(3):
                if bn[b, a] > 1:
                    c *= 2
            n_kids += c
    k0 = np.empty((n_kids, 3), np.int64)
    kn = np.empty((n_kids, 3), np.int64)
    ks = np.empty((n_kids, 3), np.int8)
    kw = np.empty((n_kids, 3, 3), np.int64)
    m = 0
    for b in range(nb):
        if not keep[b]:
            continue
        for d in range(8):
            ok = True
            for a in range(3):
                if (d >> (2 - a)) & 1 and bn[b, a] == 1:
                    ok = False
            if not ok:
                continue
            for a in range(3):
                half = (bn[b, a] + 1) // 2
                if bn[b, a] == 1:
                    k0[m, a] = b0[b, a]
                    kn[m, a] = 1
                elif (d >> (2 - a)) & 1:
                    k0[m, a] = b0[b, a] + half
                    kn[m, a] = bn[b, a] - half
                else:
                    k0[m, a] = b0[b, a]
                    kn[m, a] = half
            for i in range(3):
                ks[m, i] = state[b, i]
                for j in range(3):
                    kw[m, i, j] = win[b, i, j]
            m += 1
    return k0, kn, ks, kw


def run_blocks(shape: tuple[int, int, int], axes: tuple[np.ndarray, np.ndarray, np.ndarray], h: float,
               args: tuple, ny_eval: int, all_chains: bool, progress: Reporter | None = None,
               cancel: CancelToken = None) -> np.ndarray:
    """Per-voxel chain masks on the grid's columns ``y < ny_eval`` (the rest is left 0 for the
    caller's mirror step), decided coarse to fine (see the module docstring).

    Args:
        shape: grid shape; ``axes``: its voxel-centre coordinates; ``h``: the voxel edge.
        args: the kernel constants of :func:`kinematics.kernel_args.kernel_args`.
        ny_eval: number of y columns to compute (all of them without the mirror).
        all_chains: decide every chain (diagnostics: identical per-chain bits to the dense engine);
            otherwise a voxel's mask is exact only in whether it equals 7.
    Returns:
        uint8 array of ``shape``: bit ``i`` set where chain ``i`` is feasible.
    """
    u, cos_t, sin_t, arc, hb, rho_lo, rho_hi, lmin2, lmax2, jc = args
    lmin, lmax = math.sqrt(lmin2), math.sqrt(lmax2)
    xs, ys, zs = (np.ascontiguousarray(a, dtype=np.float64) for a in axes)
    eps = rounding_margin(lmax, (xs, ys, zs))
    out = np.zeros(shape, np.uint8)
    sub = (shape[0], ny_eval, shape[2])
    b0, bn = _top_blocks(sub, TOP_BLOCK)
    state = np.zeros((b0.shape[0], 3), np.int8)
    win = initial_windows(b0.shape[0], cos_t.shape[1])
    seg_k, seg_arc = sub_arcs(cos_t, sin_t)
    level = 0
    while b0.shape[0]:
        check(cancel)
        step = 65536  # blocks per launch: progress/cancel granularity of a few ms
        for s in range(0, b0.shape[0], step):
            check(cancel)
            with KERNEL_LOCK:
                _classify_kernel(b0[s:s + step], bn[s:s + step], state[s:s + step], win[s:s + step], xs, ys, zs,
                                 float(h), eps, bool(all_chains), u, cos_t, sin_t, arc, seg_k, seg_arc, hb, rho_lo,
                                 rho_hi, lmin, lmax, jc)
        n_before = b0.shape[0]
        with kernel_launch(n_before):
            # fail_bit given (as the bracket gives it): one compiled signature for both callers
            b0, bn, state, win = _advance(b0, bn, state, win, bool(all_chains), out, 0)
        level += 1
        if progress is not None:
            frac = min(1.0, level / LEVELS)
            nxt = f", {b0.shape[0]:,} smaller ones near the boundary next" if b0.shape[0] else ""
            progress(frac, f"computing the workspace, {100 * frac:.0f} % (level {level} of {LEVELS}: "
                           f"{n_before:,} blocks tested{nxt})")
    return out
