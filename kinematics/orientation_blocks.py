"""Reachability at EVERY orientation of a sample set, on a grid: blocks of positions excluded by
one orientation, voxels certified by groups of orientations from their neighbour's cut of the tree.

Lemma (block exclusion, :mod:`kinematics.blocks`). Let a block be a box of voxel centres with
centre ``Pc`` and half-diagonal ``delta``. At a fixed carriage pose every leg length moves by at
most ``|P - Pc| <= delta`` over the block, so if at a sample rotation ``R`` chain ``i`` fails at
``Pc`` with the leg limits relaxed by ``delta + eps`` (the blocks engine's all-fail test, ``eps``
of :func:`kinematics.blocks.rounding_margin`), it fails with the exact limits at every ``P`` of the
block at ``R``: no position of the block is in the result, and none is tested again.

Lemma (group certificate, :mod:`kinematics.orientation_tree`). For a node of the orientation tree
(a group ``G`` of samples with centre ``R0`` and chain slack ``e_i = max_{R in G, u} |R u - R0 u|``),
a carriage pose that keeps both legs of chain ``i`` in the limits tightened by ``e_i + eps`` at
``(P, R0)`` serves chain ``i`` at every ``(P, R)``, ``R in G``.

Algorithm. The candidate voxels (those of the position workspace) are covered by top blocks of
:data:`TOP_BLOCK` voxels per edge, one parallel iteration each, visited depth first: a block
without candidates is skipped; a block that one of the ``first`` hardest samples excludes (first
lemma) is dropped whole; a hardest sample at which a chain passes at the block's centre with the
leg limits tightened by ``delta + eps`` (at its last passing carriage sample: the blocks engine's
all-succeed test) is certified for the whole block, and neither its children nor its voxels test
that chain there again; any other block is split in eight (halving each edge of more than one
voxel, as the blocks engine does). A single voxel is tested exactly first at the (sample, chain)
that made the last failing voxel of its top block fail (a neighbour fails mostly at the same one:
a voxel that fails costs one test), then at the ``first`` samples, then
chain by chain over the tree: instead of walking down from the root, it starts from the **cut**
(the set of nodes whose certificates covered every sample) that the previously decided voxel of
the same top block left -- a neighbour, so mostly the same cut certifies -- opening a node whose
certificate fails down to exact single-sample tests; a pair of sibling nodes of the cut is first
tried as their parent (at the parent's last passing carriage sample only), so the cut can also
grow coarser again. Any cut covers every sample, so a voxel passes exactly when every sample's
exact test passes: each decision is either an exact test or certified by a lemma, and the voxels
are those of testing every sample at every candidate (the tests compare them with the per-pair
path). Each tree node keeps, per chain, the carriage sample that last passed there (the hint its
certificate and exact test try first). Plain model only (no joint cones, no leg interference),
like the orientation tree.

Mirror. With the centered arc range the mechanism is symmetric under ``y -> -y`` (chain 1 onto
itself, chains 2 and 3 swapped), and the sample sets of :func:`kinematics.dexterous.orientation_samples`
are closed under ``R -> D R D``, ``D = diag(1, -1, 1)``: ``(phi, theta, sigma) -> (-phi, theta,
-sigma)``. A voxel then passes every sample exactly when its mirror image does, so only the rows
``j >= ny // 2`` are decided and the others copied (:func:`reachable_on_grid`, ``mirror``), after
checking the y axis, the candidates and the rotations (:func:`mirror_closed`).
"""

from __future__ import annotations

import math

import numba
import numpy as np
from numba import njit, prange

from .blocks import FAIL, decide_chain, rounding_margin, sub_arcs
from .design import Design
from .feasibility import _feasible_at, chain_points
from .kernel_args import kernel_args
from .orientation_tree import _certified, _exact, build_tree, node_slack
from .parallel import kernel_launch
from .progress import CancelToken, Reporter, check
from .summed_volume import box_count, summed_volume
from .workspace import rotation_tables

#: Edge (in voxels) of the coarsest position blocks (each voxel's cut and hints start afresh in a
#: top block: at h = 4, 657 orientations, 64 cost 0.9x the CPU time of 32, 16 1.1x).
TOP_BLOCK = 64
#: Top blocks per kernel launch at the default 15/15 deg set's 657 orientations (cancellation and
#: progress are checked between launches; :func:`launch_blocks`).
LAUNCH = 16
#: Orientations x top blocks of one launch (:func:`launch_blocks`).
LAUNCH_WORK = LAUNCH * 657


def launch_blocks(n_orientations: int, threads: int) -> int:
    """Top blocks per kernel launch for a set of ``n_orientations``: :data:`LAUNCH` at the default
    set's 657, fewer for a larger set so that a launch holds about :data:`LAUNCH_WORK` block-
    orientations (a Stop waited 15 s for a launch of 16 blocks at 352,557 orientations), and never
    fewer than one per thread."""
    return max(1, int(threads), min(LAUNCH, LAUNCH_WORK // max(1, int(n_orientations))))


@njit(cache=True, nogil=True)
def _excluded(px, py, pz, delta, eps, first, us, jcs, cos_t, sin_t, arc, seg_k, seg_arc, hb, rho_lo, rho_hi, lmin,
              lmax, hints, win, done):
    """Whether one of the samples ``0 .. first - 1`` excludes the whole block (centre ``P``,
    half-diagonal ``delta``): the excluded test of the module docstring, stopped at the first
    sample that passes relaxed (``hints[m, i]``: chain ``i``'s last passing sample at sample ``m``).
    A chain that passes at its hint with the limits tightened by ``delta + eps`` passes at every
    voxel of the block (the blocks engine's all-succeed test): ``done[m, i]`` is set, and neither
    the block's children nor its voxels test it again."""
    e = delta + eps
    n_eta = cos_t.shape[1]
    lo_t, hi_t = lmin + e, lmax - e
    for m in range(first):
        for i in range(3):
            if done[m, i]:
                continue
            k = hints[m, i]
            b1x, b1y, b1z, b2x, b2y, b2z = chain_points(px, py, pz, us[m], i)
            if lo_t <= hi_t and _feasible_at(b1x, b1y, b1z, b2x, b2y, b2z, cos_t[i, k], sin_t[i, k], hb, rho_lo,
                                             rho_hi, lo_t * lo_t, hi_t * hi_t, jcs[m][i], 0.0):
                done[m, i] = True
                continue
            win[0] = k
            win[1] = 0
            win[2] = n_eta - 1
            if decide_chain(px, py, pz, us[m], i, cos_t, sin_t, arc, seg_k, seg_arc, hb, rho_lo, rho_hi, lmin, lmax,
                            jcs[m], e + eps, e, e, e, False, win) == FAIL:
                return True
            hints[m, i] = win[0]
    return False


@njit(cache=True, nogil=True)
def _voxel(px, py, pz, first, us, jcs, left, right, parent, leaf, centre, lo2, hi2, cos_t, sin_t, arc, hb, rho_lo,
           rho_hi, lmin2, lmax2, hints, cut, n_cut, new_cut, stack, done, fail):
    """Whether the voxel centre ``P`` passes the exact test at every sample: first the (single-sample
    node, chain) that failed last (``fail``, updated), then the samples ``0 .. first - 1`` one by
    one, then per chain the tree from the cut its neighbour left (``cut[i, :n_cut[i]]``, updated
    when the voxel passes; a pair of sibling nodes is tried as their parent first). ``hints``
    (nodes, 3): each chain's last passing sample per node; ``done`` (first, 3): the pairs its blocks
    already certified."""
    f, fi = fail[0], fail[1]
    if f >= 0:
        m = leaf[f]
        if not (m < first and done[m, fi]) and not _exact(px, py, pz, us[m], fi, cos_t, sin_t, arc, hb, rho_lo,
                                                          rho_hi, lmin2, lmax2, jcs[m], hints[f]):
            return False
    for m in range(first):
        nd = left.shape[0] - first + m
        for i in range(3):
            if not done[m, i] and not (nd == f and i == fi) and not _exact(
                    px, py, pz, us[m], i, cos_t, sin_t, arc, hb, rho_lo, rho_hi, lmin2, lmax2, jcs[m], hints[nd]):
                fail[0], fail[1] = nd, i
                return False
    if left.shape[0] == first:
        return True
    for i in range(3):
        top = -1
        j = n_cut[i] - 1
        while j >= 0:
            nd = cut[i, j]
            p = parent[nd]
            top += 1
            if p >= 0 and j >= 1 and right[p] == nd and cut[i, j - 1] == left[p]:
                stack[top] = -1 - p  # the parent, at its last passing sample only
                j -= 2
            else:
                stack[top] = nd
                j -= 1
        nn = 0
        while top >= 0:
            nd = stack[top]
            top -= 1
            if nd < 0:
                nd = -1 - nd
                c = centre[nd]
                b1x, b1y, b1z, b2x, b2y, b2z = chain_points(px, py, pz, us[c], i)
                k = hints[nd, i]
                if hi2[nd, i] >= 0.0 and _feasible_at(b1x, b1y, b1z, b2x, b2y, b2z, cos_t[i, k], sin_t[i, k], hb,
                                                      rho_lo, rho_hi, lo2[nd, i], hi2[nd, i], jcs[c][i], 0.0):
                    new_cut[nn] = nd
                    nn += 1
                else:
                    top += 1
                    stack[top] = right[nd]
                    top += 1
                    stack[top] = left[nd]
                continue
            m = leaf[nd]
            if m >= 0:
                if not (nd == f and i == fi) and not _exact(px, py, pz, us[m], i, cos_t, sin_t, arc, hb, rho_lo,
                                                            rho_hi, lmin2, lmax2, jcs[m], hints[nd]):
                    fail[0], fail[1] = nd, i
                    return False
            elif not (hi2[nd, i] >= 0.0 and _certified(px, py, pz, us[centre[nd]], i, cos_t, sin_t, arc, hb, rho_lo,
                                                       rho_hi, lo2[nd, i], hi2[nd, i], jcs[centre[nd]], hints[nd])):
                top += 1
                stack[top] = right[nd]
                top += 1
                stack[top] = left[nd]
                continue
            new_cut[nn] = nd
            nn += 1
        n_cut[i] = nn
        cut[i, :nn] = new_cut[:nn]
    return True


@njit(parallel=True, cache=True, nogil=True)
def _blocks_kernel(t0, tn, cand, cum, xs, ys, zs, h, eps, first, levels, us, jcs, left, right, parent, leaf, centre,
                   lo2, hi2, cos_t, sin_t, arc, seg_k, seg_arc, hb, rho_lo, rho_hi, lmin, lmax, out):
    """The algorithm of the module docstring for each top block ``t0[t]`` (``tn[t]`` voxels per
    axis), depth first; ``out`` (grid shape) is set where a candidate passes every sample. The tree's
    nodes come first, the ``first`` single-sample nodes last."""
    n_nodes = left.shape[0]
    n_eta = cos_t.shape[1]
    for t in prange(t0.shape[0]):
        hints = np.full((n_nodes, 3), n_eta // 2, np.int64)
        cut = np.zeros((3, n_nodes), np.int64)  # the tree's root
        n_cut = np.ones(3, np.int64)
        new_cut = np.empty(n_nodes, np.int64)
        stack = np.empty(n_nodes + 64, np.int64)
        win = np.empty(3, np.int64)
        fail = np.full(2, -1, np.int64)  # the (single-sample node, chain) that failed last
        cap = 8 * levels + 8
        b0 = np.empty((cap, 3), np.int64)
        bn = np.empty((cap, 3), np.int64)
        done = np.zeros((cap, max(first, 1), 3), np.bool_)  # per block: the first samples' chains certified
        sp = 0
        for a in range(3):
            b0[0, a] = t0[t, a]
            bn[0, a] = tn[t, a]
        while sp >= 0:
            x0, y0, z0 = b0[sp, 0], b0[sp, 1], b0[sp, 2]
            nx, ny, nz = bn[sp, 0], bn[sp, 1], bn[sp, 2]
            mine = done[sp].copy()
            sp -= 1
            if box_count(cum, x0, y0, z0, x0 + nx, y0 + ny, z0 + nz) == 0:
                continue
            px = 0.5 * (xs[x0] + xs[x0 + nx - 1])
            py = 0.5 * (ys[y0] + ys[y0 + ny - 1])
            pz = 0.5 * (zs[z0] + zs[z0 + nz - 1])
            if nx == 1 and ny == 1 and nz == 1:
                out[x0, y0, z0] = _voxel(px, py, pz, first, us, jcs, left, right, parent, leaf, centre, lo2, hi2,
                                         cos_t, sin_t, arc, hb, rho_lo, rho_hi, lmin * lmin, lmax * lmax,
                                         hints, cut, n_cut, new_cut, stack, mine, fail)
                continue
            delta = 0.5 * h * math.sqrt((nx - 1) ** 2 + (ny - 1) ** 2 + (nz - 1) ** 2)
            if _excluded(px, py, pz, delta, eps, first, us, jcs, cos_t, sin_t, arc, seg_k, seg_arc, hb, rho_lo,
                         rho_hi, lmin, lmax, hints[n_nodes - first:], win, mine):
                continue
            # children (first half gets the extra voxel)
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
                done[sp] = mine


def _even_top_blocks(shape: tuple[int, int, int], size: int) -> tuple[np.ndarray, np.ndarray]:
    """Top blocks of at most ``size`` voxels per edge. Along x and y each axis is cut into
    ``ceil(n / size)`` equal parts (within one voxel): a grid of 98 gives two blocks of 49, not 64 and
    34, so the threads that take the blocks get even shares of a workspace centred on the z axis
    (h = 4: 0.79x the time of the plain cut, with 2 threads). Along z the plain cut of
    :func:`kinematics.blocks._top_blocks` is kept (equal parts there were slower at h = 2)."""
    per_axis = []
    for k, n in enumerate(shape):
        p = max(1, -(-n // size))
        edges = (np.arange(p + 1) * n) // p if k < 2 else np.minimum(np.arange(p + 1) * size, n)
        per_axis.append((edges[:-1], np.diff(edges)))
    g0 = np.meshgrid(*(e for e, _ in per_axis), indexing="ij")
    gn = np.meshgrid(*(w for _, w in per_axis), indexing="ij")
    b0 = np.stack([g.ravel() for g in g0], axis=1).astype(np.int64)
    bn = np.stack([g.ravel() for g in gn], axis=1).astype(np.int64)
    return b0, bn


def mirror_closed(rotations: np.ndarray, tol: float = 1e-12) -> bool:
    """Whether the set of ``rotations`` (M, 3, 3) is closed under the mirror ``y -> -y``, ``R -> D R D``
    with ``D = diag(1, -1, 1)`` (for T&T angles ``(phi, theta, sigma) -> (-phi, theta, -sigma)``):
    every mirrored rotation equals one of the set to within ``tol`` in every entry."""
    r = np.asarray(rotations, dtype=np.float64).reshape(-1, 3, 3)
    d = np.array([1.0, -1.0, 1.0])
    a = r.reshape(len(r), 9)
    b = (r * d[None, :, None] * d[None, None, :]).reshape(len(r), 9)
    # look each mirrored rotation up by its entries rounded to 1e-9, then check it within tol (a
    # rotation whose entries round the other way is not found: then no mirror, never a wrong one)
    void = np.dtype((np.void, 9 * 8))
    ka = np.ascontiguousarray(np.round(a * 1e9).astype(np.int64)).view(void).ravel()
    kb = np.ascontiguousarray(np.round(b * 1e9).astype(np.int64)).view(void).ravel()
    order = np.argsort(ka, kind="stable")
    pos = np.minimum(np.searchsorted(ka[order], kb), len(ka) - 1)
    k = order[pos]
    return bool(np.all(ka[k] == kb) and np.abs(a[k] - b).max() <= tol)


def reachable_on_grid(design: Design, candidates: np.ndarray, axes: tuple[np.ndarray, np.ndarray, np.ndarray],
                      h: float, samples: np.ndarray, rotations: np.ndarray, n_eta: int, first: int = 0,
                      progress: Reporter | None = None, cancel: CancelToken = None,
                      mirror: bool = False) -> np.ndarray:
    """Whether each candidate voxel (``candidates``: bool grid; ``axes``: its voxel-centre
    coordinates, edge ``h``) passes the exact per-pair test at every rotation of ``rotations``
    (M, 3, 3; ``samples`` their (azimuth, tilt, torsion) rows), plain model only: bool grid, False
    off the candidates. The first ``first`` samples exclude blocks and are tested first (module
    docstring).

    ``mirror``: the design is symmetric under ``y -> -y`` (the engine's mirror: the centered arc
    range). Where the candidates and the y axis are symmetric too and the rotations are closed under
    the mirror (:func:`mirror_closed`), a voxel passes every rotation exactly when its mirror image
    does (it meets the mirrored rotation there), so only the rows ``j >= ny // 2`` are decided and
    the others are copied from their mirror rows: half the work, as the engine does."""
    from .joints import Joints

    cand = np.ascontiguousarray(np.asarray(candidates, dtype=np.bool_))
    ny = cand.shape[1]
    ys = np.asarray(axes[1], dtype=np.float64)
    mirror = bool(mirror and ny > 1 and np.allclose(ys, -ys[::-1], atol=1e-9 * max(1.0, h))
                  and np.array_equal(cand, cand[:, ::-1]) and mirror_closed(rotations))
    if mirror:
        cand = cand.copy()
        cand[:, :ny // 2] = False
        out = reachable_on_grid(design, cand, axes, h, samples, rotations, n_eta, first, progress, cancel)
        out[:, :ny // 2] = out[:, ::-1][:, :ny // 2]
        return out
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
    left, right, leaf, centre, perm, lo, hi = build_tree(samples, rots, first, cancel)
    # the first samples as single-sample nodes after the tree's
    singles = np.arange(first, dtype=np.int64)
    left = np.concatenate([left, np.full(first, -1, np.int64)])
    right = np.concatenate([right, np.full(first, -1, np.int64)])
    leaf = np.concatenate([leaf, singles])
    centre = np.concatenate([centre, singles])
    lo = np.concatenate([lo, perm.size + singles])
    hi = np.concatenate([hi, perm.size + singles + 1])
    perm = np.concatenate([perm, singles])
    slack = node_slack(us, perm, lo, hi, centre) + eps
    lo2 = (lmin + slack) ** 2
    hi2 = np.where((lmin + slack <= lmax - slack) & (leaf < 0)[:, None], (lmax - slack) ** 2, -1.0)
    parent = np.full(left.size, -1, np.int64)
    inner = np.flatnonzero(left >= 0)
    parent[left[inner]] = inner
    parent[right[inner]] = inner
    cum = summed_volume(cand)
    t0, tn = _even_top_blocks(cand.shape, TOP_BLOCK)
    x0, y0, z0 = t0.T
    x1, y1, z1 = (t0 + tn).T
    counts = box_count.py_func(cum, x0, y0, z0, x1, y1, z1)  # numpy's indexing: every top block at once
    t0, tn = t0[counts > 0], tn[counts > 0]
    levels = int(math.ceil(math.log2(TOP_BLOCK))) + 1
    seg_k, seg_arc = sub_arcs(cos_t, sin_t)
    per = launch_blocks(rots.shape[0], numba.get_num_threads())
    for s in range(0, t0.shape[0], per):
        check(cancel)
        sl = slice(s, min(t0.shape[0], s + per))
        with kernel_launch(sl.stop - sl.start):
            _blocks_kernel(t0[sl], tn[sl], cand, cum, xs, ys, zs, float(h), eps, first, levels, us, jcs, left, right,
                           parent, leaf, centre, lo2, hi2, cos_t, sin_t, arc, seg_k, seg_arc, hb, rho_lo, rho_hi, lmin,
                           lmax, out)
        if progress is not None:
            progress(sl.stop / t0.shape[0], "total-orientation workspace")
    return out
