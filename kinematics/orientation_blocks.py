"""Reachability at EVERY orientation of a sample set, decided by blocks of positions x groups of orientations.

Lemma (joint slack). Let a block be a box of voxel centres with centre ``Pc`` and half-diagonal
``delta`` (:mod:`kinematics.blocks`), and a node of the orientation tree
(:mod:`kinematics.orientation_tree`) a group ``G`` of sample rotations with centre ``R0`` in ``G``
and chain slack ``e_i = max_{R in G, u} |R u - R0 u|``. At a fixed carriage pose the U joints do not
move, and the S joint ``B = P + R u`` moves by at most ``|P - Pc| + |R u - R0 u| <= delta + e_i``,
so every leg length of chain ``i`` at ``(P, R)``, ``P`` in the block and ``R`` in ``G``, is within
``delta + e_i`` of the one at ``(Pc, R0)``. With ``eps`` (:func:`kinematics.blocks.rounding_margin`):

* **certified**: if some arc sample admits a ``rho`` with both legs of chain ``i`` in the range
  tightened by ``delta + e_i + eps`` at ``(Pc, R0)``, the same carriage pose serves chain ``i`` with
  the exact limits at every ``(P, R)`` of block x group;
* **excluded**: ``R0`` is itself a sample; if at ``(Pc, R0)`` chain ``i`` fails with the limits
  relaxed by ``delta + eps`` (the blocks engine's all-fail test), it fails with the exact limits at
  every ``P`` of the block at ``R0``, so no position of the block is in the result.

Recursion on both. A block carries a **frontier**: the tree nodes (each with the chains already
certified for it) still to be shown for all its positions. A block walks its frontier depth first:
a chain is certified (lemma), or at a single sample the excluded test runs (a block excluded by
one sample is dropped whole: its positions are never tested again at any other orientation); a
node left with a chain is opened when its largest open slack ``e_i`` exceeds ``delta`` (the group
is the worse of the two), and otherwise kept for the block's eight children (halving each edge of
more than one voxel, as the blocks engine), which start from the parent's frontier. A block whose
frontier empties is inside for every candidate voxel it holds; a block without candidates (voxels
of the position workspace) is skipped. A single voxel walks its frontier with ``delta = 0``: the
exact per-sample test at single samples and the tree's certificate elsewhere, the point walk of
:mod:`kinematics.orientation_tree`. Every decision is either exact or certified by the lemma, so
the voxels are those of testing every sample at every candidate exactly (the tests compare them
with the per-pair path). The ``first`` hardest samples are single-sample nodes at the head of the
initial frontier, before the tree's root: most blocks that leave, leave at one of them. Plain model
only (no joint cones, no leg interference), like the orientation tree. The top blocks are
independent: one parallel iteration each.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit, prange

from .blocks import FAIL, OK, _top_blocks, decide_chain, rounding_margin, sub_arcs
from .design import Design
from .kernel_args import kernel_args
from .orientation_tree import _certified, _exact, build_tree
from .parallel import kernel_launch
from .progress import CancelToken, Reporter, check
from .workspace import rotation_tables

#: Edge (in voxels) of the coarsest position blocks.
TOP_BLOCK = 8
#: Top blocks per kernel launch (cancellation and progress are checked between launches).
LAUNCH = 256


@njit(cache=True, nogil=True)
def _walk(px, py, pz, delta, eps, pool, f0, f1, o0, stack, us, jcs, left, right, leaf, centre, slack, cos_t,
          sin_t, arc, seg_k, seg_arc, hb, rho_lo, rho_hi, lmin, lmax, hint, win):
    """Walk the frontier ``pool[f0:f1]`` (rows ``(node, certified chain bits)``) for the block with
    centre ``P`` and half-diagonal ``delta`` (0: a single voxel, exact). Returns -1 when the block is
    excluded, else the number of rows of its children's frontier written to ``pool[o0:]`` (0: every
    position of the block passes every sample of the frontier)."""
    n_eta = cos_t.shape[1]
    lmin2, lmax2 = lmin * lmin, lmax * lmax
    e_blk = delta + eps
    top = -1
    for q in range(f1 - 1, f0 - 1, -1):
        top += 1
        stack[top, 0] = pool[q, 0]
        stack[top, 1] = pool[q, 1]
    n_out = 0
    while top >= 0:
        nd = stack[top, 0]
        bits = stack[top, 1]
        top -= 1
        m = leaf[nd]
        worst = 0.0
        for i in range(3):
            if (bits >> i) & 1:
                continue
            if m >= 0:
                if delta == 0.0:
                    if not _exact(px, py, pz, us[m], i, cos_t, sin_t, arc, hb, rho_lo, rho_hi, lmin2, lmax2, jcs[m],
                                  hint):
                        return -1
                    bits |= 1 << i
                    continue
                win[0] = hint[i]
                win[1] = 0
                win[2] = n_eta - 1
                s = decide_chain(px, py, pz, us[m], i, cos_t, sin_t, arc, seg_k, seg_arc, hb, rho_lo, rho_hi, lmin,
                                 lmax, jcs[m], e_blk + eps, e_blk, e_blk, e_blk, True, win)
                hint[i] = win[0]
                if s == FAIL:
                    return -1
                if s == OK:
                    bits |= 1 << i
            else:
                e = slack[nd, i] + delta
                lo, hi = lmin + e, lmax - e
                c = centre[nd]
                if lo <= hi and _certified(px, py, pz, us[c], i, cos_t, sin_t, arc, hb, rho_lo, rho_hi, lo * lo,
                                           hi * hi, jcs[c], hint):
                    bits |= 1 << i
                else:
                    worst = max(worst, slack[nd, i])
        if bits == 7:
            continue
        if m < 0 and (delta == 0.0 or worst > delta):
            top += 1
            stack[top, 0] = right[nd]
            stack[top, 1] = bits
            top += 1
            stack[top, 0] = left[nd]
            stack[top, 1] = bits
        else:
            pool[o0 + n_out, 0] = nd
            pool[o0 + n_out, 1] = bits
            n_out += 1
    return n_out


@njit(cache=True, inline="always")
def _count(cum, x0, y0, z0, x1, y1, z1):
    """Candidates in the voxels ``[x0, x1) x [y0, y1) x [z0, z1)`` (``cum``: summed-volume table)."""
    return (cum[x1, y1, z1] - cum[x0, y1, z1] - cum[x1, y0, z1] - cum[x1, y1, z0]
            + cum[x0, y0, z1] + cum[x0, y1, z0] + cum[x1, y0, z0] - cum[x0, y0, z0])


@njit(parallel=True, cache=True, nogil=True)
def _blocks_kernel(t0, tn, cand, cum, xs, ys, zs, h, eps, init, levels, us, jcs, left, right, leaf, centre, slack,
                   cos_t, sin_t, arc, seg_k, seg_arc, hb, rho_lo, rho_hi, lmin, lmax, out):
    """The recursion of the module docstring for each top block ``t0[t]`` (``tn[t]`` voxels per
    axis), depth first, from the frontier ``init``; ``out`` (grid shape) is set where a candidate
    passes every sample."""
    n_nodes = left.shape[0]
    for t in prange(t0.shape[0]):
        pool = np.empty(((levels + 1) * n_nodes + init.shape[0], 2), np.int64)
        stack = np.empty((n_nodes + init.shape[0] + 64, 2), np.int64)
        cap = 8 * levels + 8
        b0 = np.empty((cap, 3), np.int64)
        bn = np.empty((cap, 3), np.int64)
        bf = np.empty((cap, 2), np.int64)  # the block's frontier rows in the pool
        hint = np.full(3, cos_t.shape[1] // 2, np.int64)
        win = np.empty(3, np.int64)
        for q in range(init.shape[0]):
            pool[q, 0] = init[q, 0]
            pool[q, 1] = init[q, 1]
        sp = 0
        for a in range(3):
            b0[0, a] = t0[t, a]
            bn[0, a] = tn[t, a]
        bf[0, 0] = 0
        bf[0, 1] = init.shape[0]
        while sp >= 0:
            x0, y0, z0 = b0[sp, 0], b0[sp, 1], b0[sp, 2]
            nx, ny, nz = bn[sp, 0], bn[sp, 1], bn[sp, 2]
            f0, f1 = bf[sp, 0], bf[sp, 1]
            sp -= 1
            # the pool above this block's frontier belongs to finished siblings' subtrees (LIFO)
            o0 = f1
            if _count(cum, x0, y0, z0, x0 + nx, y0 + ny, z0 + nz) == 0:
                continue
            px = 0.5 * (xs[x0] + xs[x0 + nx - 1])
            py = 0.5 * (ys[y0] + ys[y0 + ny - 1])
            pz = 0.5 * (zs[z0] + zs[z0 + nz - 1])
            delta = 0.5 * h * math.sqrt((nx - 1) ** 2 + (ny - 1) ** 2 + (nz - 1) ** 2)
            r = _walk(px, py, pz, delta, eps, pool, f0, f1, o0, stack, us, jcs, left, right, leaf, centre, slack,
                      cos_t, sin_t, arc, seg_k, seg_arc, hb, rho_lo, rho_hi, lmin, lmax, hint, win)
            if r < 0:
                continue
            if r == 0:
                for x in range(x0, x0 + nx):
                    for y in range(y0, y0 + ny):
                        for z in range(z0, z0 + nz):
                            if cand[x, y, z]:
                                out[x, y, z] = True
                continue
            # children (first half gets the extra voxel), all starting from the new frontier
            hx, hy, hz = (nx + 1) // 2, (ny + 1) // 2, (nz + 1) // 2
            for d in range(7, -1, -1):
                dx, dy, dz = (d >> 2) & 1, (d >> 1) & 1, d & 1
                if (dx and nx == 1) or (dy and ny == 1) or (dz and nz == 1):
                    continue
                sp += 1
                b0[sp, 0] = x0 + dx * hx
                b0[sp, 1] = y0 + dy * hy
                b0[sp, 2] = z0 + dz * hz
                bn[sp, 0] = (nx - hx if dx else hx) if nx > 1 else 1
                bn[sp, 1] = (ny - hy if dy else hy) if ny > 1 else 1
                bn[sp, 2] = (nz - hz if dz else hz) if nz > 1 else 1
                bf[sp, 0] = o0
                bf[sp, 1] = o0 + r


def reachable_on_grid(design: Design, candidates: np.ndarray, axes: tuple[np.ndarray, np.ndarray, np.ndarray],
                      h: float, samples: np.ndarray, rotations: np.ndarray, n_eta: int, first: int = 0,
                      progress: Reporter | None = None, cancel: CancelToken = None) -> np.ndarray:
    """Whether each candidate voxel (``candidates``: bool grid; ``axes``: its voxel-centre
    coordinates, edge ``h``) passes the exact per-pair test at every rotation of ``rotations``
    (M, 3, 3; ``samples`` their (azimuth, tilt, torsion) rows), plain model only: bool grid, False
    off the candidates. The first ``first`` samples lead the initial frontier (module docstring)."""
    from .joints import Joints

    cand = np.ascontiguousarray(np.asarray(candidates, dtype=np.bool_))
    out = np.zeros(cand.shape, np.bool_)
    rots = np.ascontiguousarray(np.asarray(rotations, dtype=np.float64).reshape(-1, 3, 3))
    if not cand.any():
        return out
    if not rots.shape[0]:
        return cand.copy()
    xs, ys, zs = (np.ascontiguousarray(a, dtype=np.float64) for a in axes)
    _u, cos_t, sin_t, arc, hb, rho_lo, rho_hi, lmin2, lmax2, _ = kernel_args(design, np.eye(3), n_eta)
    us, jcs = rotation_tables(design, rots, Joints())
    lmin, lmax = math.sqrt(lmin2), math.sqrt(lmax2)
    eps = rounding_margin(lmax, (xs, ys, zs))
    first = min(int(first), rots.shape[0])
    if first < rots.shape[0]:
        left, right, leaf, centre, members = build_tree(samples[first:], rots[first:])
        leaf = np.where(leaf >= 0, leaf + first, -1)
        centre = centre + first
        members = [m + first for m in members]
    else:
        left = right = leaf = centre = np.zeros(0, np.int64)
        members = []
    # the first samples as single-sample nodes after the tree's
    n_tree = left.size
    left = np.concatenate([left, np.full(first, -1, np.int64)])
    right = np.concatenate([right, np.full(first, -1, np.int64)])
    leaf = np.concatenate([leaf, np.arange(first, dtype=np.int64)])
    centre = np.concatenate([centre, np.arange(first, dtype=np.int64)])
    members = members + [np.array([m]) for m in range(first)]
    slack = np.array([[float(np.linalg.norm(us[m, i] - us[c, i], axis=-1).max()) for i in range(3)]
                      for m, c in zip(members, centre)]).reshape(-1, 3) + eps
    init = np.zeros((first + (1 if n_tree else 0), 2), np.int64)
    init[:first, 0] = n_tree + np.arange(first)
    if n_tree:
        init[first, 0] = 0
    cum = np.zeros(tuple(n + 1 for n in cand.shape), np.int64)
    cum[1:, 1:, 1:] = cand.cumsum(0).cumsum(1).cumsum(2)
    t0, tn = _top_blocks(cand.shape, TOP_BLOCK)
    counts = np.array([cand[a:a + p, b:b + q, c:c + r].sum() for (a, b, c), (p, q, r) in zip(t0, tn)])
    t0, tn = t0[counts > 0], tn[counts > 0]
    levels = int(math.ceil(math.log2(TOP_BLOCK))) + 1
    seg_k, seg_arc = sub_arcs(cos_t, sin_t)
    for s in range(0, t0.shape[0], LAUNCH):
        check(cancel)
        sl = slice(s, min(t0.shape[0], s + LAUNCH))
        with kernel_launch(sl.stop - sl.start):
            _blocks_kernel(t0[sl], tn[sl], cand, cum, xs, ys, zs, float(h), eps, init, levels, us, jcs, left, right,
                           leaf, centre, slack, cos_t, sin_t, arc, seg_k, seg_arc, hb, rho_lo, rho_hi, lmin, lmax,
                           out)
        if progress is not None:
            progress(sl.stop / t0.shape[0], "total-orientation workspace")
    return out
