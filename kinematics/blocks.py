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
from typing import Optional

import numpy as np
from numba import njit, prange

from .feasibility import _chain_excluded, _feasible_at, chain_points, chain_search
from .parallel import KERNEL_LOCK
from .progress import CancelToken, Reporter, check

__all__ = ["run_blocks", "TOP_BLOCK"]

#: Edge (in voxels) of the coarsest blocks.
TOP_BLOCK = 16

UNKNOWN, OK, FAIL = 0, 1, 2


@njit(cache=True, inline="always")
def _chain_state(px, py, pz, u, i, cos_t, sin_t, arc, hb, rho_lo, rho_hi, lmin, lmax, jc, e):
    """OK / FAIL / UNKNOWN for chain ``i`` over the ball of radius ``e`` around P (see module doc);
    ``e = 0`` is the dense test at P itself."""
    b1x, b1y, b1z, b2x, b2y, b2z = chain_points(px, py, pz, u, i)
    n = cos_t.shape[1]
    lo_r = max(lmin - e, 0.0)
    hi_r = lmax + e
    if _chain_excluded(b1x, b1y, b1z, b2x, b2y, b2z, hb, arc[i], rho_lo, rho_hi, lo_r * lo_r, hi_r * hi_r):
        return FAIL
    if e == 0.0:
        k = chain_search(b1x, b1y, b1z, b2x, b2y, b2z, cos_t[i], sin_t[i], hb, rho_lo, rho_hi,
                         lmin * lmin, lmax * lmax, jc[i], n // 2)
        return OK if k >= 0 else FAIL
    # one pass over the samples: relaxed first (the tightened set is inside it), tightened if that holds
    lo_t = lmin + e
    hi_t = lmax - e
    can_ok = lo_t <= hi_t
    lo_t2, hi_t2 = lo_t * lo_t, hi_t * hi_t
    lo_r2, hi_r2 = lo_r * lo_r, hi_r * hi_r
    some = False
    for k in range(n):
        if _feasible_at(b1x, b1y, b1z, b2x, b2y, b2z, cos_t[i, k], sin_t[i, k], hb, rho_lo, rho_hi, lo_r2, hi_r2,
                        jc[i], e):
            some = True
            if not can_ok:
                break
            if _feasible_at(b1x, b1y, b1z, b2x, b2y, b2z, cos_t[i, k], sin_t[i, k], hb, rho_lo, rho_hi,
                            lo_t2, hi_t2, jc[i], -e):
                return OK
    return UNKNOWN if some else FAIL


@njit(cache=True, inline="always")
def block_centre(b0, bn, b, xs, ys, zs):
    """Centre of block ``b``'s voxel centres (its first voxel ``b0[b]``, ``bn[b]`` voxels per axis)."""
    return (0.5 * (xs[b0[b, 0]] + xs[b0[b, 0] + bn[b, 0] - 1]),
            0.5 * (ys[b0[b, 1]] + ys[b0[b, 1] + bn[b, 1] - 1]),
            0.5 * (zs[b0[b, 2]] + zs[b0[b, 2] + bn[b, 2] - 1]))


@njit(parallel=True, cache=True, nogil=True)
def _classify_kernel(b0, bn, state, xs, ys, zs, h, eps, all_chains,
                     u, cos_t, sin_t, arc, hb, rho_lo, rho_hi, lmin, lmax, jc):
    """Decide the undecided chains of each block (in place in ``state``, shape (nb, 3))."""
    for b in prange(b0.shape[0]):
        nx, ny, nz = bn[b, 0], bn[b, 1], bn[b, 2]
        px, py, pz = block_centre(b0, bn, b, xs, ys, zs)
        single = nx == 1 and ny == 1 and nz == 1
        delta = 0.5 * h * math.sqrt((nx - 1) ** 2 + (ny - 1) ** 2 + (nz - 1) ** 2)
        e = 0.0 if single else delta + eps
        for i in range(3):
            if state[b, i] != UNKNOWN:
                continue
            s = _chain_state(px, py, pz, u, i, cos_t, sin_t, arc, hb, rho_lo, rho_hi, lmin, lmax, jc, e)
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


def _split(b0: np.ndarray, bn: np.ndarray, state: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Eight children per block (halving every edge longer than one voxel), inheriting ``state``."""
    kids0, kidsn, kidss = [], [], []
    half = (bn + 1) // 2  # first half gets the extra voxel
    for dx in (0, 1):
        for dy in (0, 1):
            for dz in (0, 1):
                d = np.array([dx, dy, dz], np.int64)[None, :]
                n = np.where(d == 0, np.where(bn > 1, half, bn), bn - half)
                keep = np.all(n > 0, axis=1)
                kids0.append((b0 + d * half)[keep])
                kidsn.append(n[keep])
                kidss.append(state[keep])
    return np.concatenate(kids0), np.concatenate(kidsn), np.concatenate(kidss)


def run_blocks(shape: tuple[int, int, int], axes: tuple[np.ndarray, np.ndarray, np.ndarray], h: float,
               args: tuple, ny_eval: int, all_chains: bool, progress: Optional[Reporter] = None,
               cancel: CancelToken = None) -> np.ndarray:
    """Per-voxel chain masks on the grid's columns ``y < ny_eval`` (the rest is left 0 for the
    caller's mirror step), decided coarse to fine (see the module docstring).

    Args:
        shape: grid shape; ``axes``: its voxel-centre coordinates; ``h``: the voxel edge.
        args: the kernel constants of :func:`kinematics.workspace._kernel_args`.
        ny_eval: number of y columns to compute (all of them without the mirror).
        all_chains: decide every chain (diagnostics: identical per-chain bits to the dense engine);
            otherwise a voxel's mask is exact only in whether it equals 7.
    Returns:
        uint8 array of ``shape``: bit ``i`` set where chain ``i`` is feasible.
    """
    u, cos_t, sin_t, arc, hb, rho_lo, rho_hi, lmin2, lmax2, jc = args
    lmin, lmax = math.sqrt(lmin2), math.sqrt(lmax2)
    xs, ys, zs = (np.ascontiguousarray(a, dtype=np.float64) for a in axes)
    eps = 1e-9 * max(1.0, lmax, float(np.abs(xs).max()), float(np.abs(ys).max()), float(np.abs(zs).max()))
    out = np.zeros(shape, np.uint8)
    sub = (shape[0], ny_eval, shape[2])
    b0, bn = _top_blocks(sub, TOP_BLOCK)
    state = np.zeros((b0.shape[0], 3), np.int8)
    level = 0
    n_levels = int(math.ceil(math.log2(TOP_BLOCK))) + 1
    while b0.shape[0]:
        check(cancel)
        step = 65536  # blocks per launch: progress/cancel granularity of a few ms
        for s in range(0, b0.shape[0], step):
            check(cancel)
            with KERNEL_LOCK:
                _classify_kernel(b0[s:s + step], bn[s:s + step], state[s:s + step], xs, ys, zs, float(h), eps,
                                 bool(all_chains), u, cos_t, sin_t, arc, hb, rho_lo, rho_hi, lmin, lmax, jc)
        fail = np.any(state == FAIL, axis=1)
        ok = np.all(state == OK, axis=1)
        single = np.all(bn == 1, axis=1)
        done = ok | (fail & ~np.bool_(all_chains)) | ~np.any(state == UNKNOWN, axis=1) | single
        bits = ((state == OK) * np.array([1, 2, 4], np.uint8)[None, :]).sum(axis=1).astype(np.uint8)
        _fill_kernel(b0[done], bn[done], bits[done], out)
        keep = ~done
        level += 1
        if progress is not None:
            progress(min(1.0, level / n_levels), f"position workspace: level {level}, {int(keep.sum())} blocks split")
        if not keep.any():
            break
        b0, bn, state = _split(b0[keep], bn[keep], state[keep])
    return out
