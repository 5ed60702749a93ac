"""Reachability of a position at EVERY orientation of a sample set, decided by groups of orientations.

Lemma (orientation slack). Let ``R0`` be a rotation and ``G`` a finite set of rotations. For the
platform points ``u`` of chain ``i`` let ``e_i = max_{R in G, u} |R u - R0 u|`` (at most ``alpha
max|u|`` when every ``R R0^T`` turns by at most ``alpha``, since ``|(R R0^T - I) v| <= 2 sin(alpha/2)
|v|``). At a fixed carriage pose (arc sample ``k``, rail coordinate ``rho``) the U joints do not
move with the platform, so every leg length of chain ``i`` at ``(P, R)``, ``R in G``, is within
``e_i`` of the one at ``(P, R0)``.

Hence, **certificate** (per chain): if some arc sample admits a ``rho`` with both legs of chain
``i`` in the tightened range ``[l_min + e_i + eps, l_max - e_i - eps]`` at ``(P, R0)``, the same
``(k, rho)`` serves chain ``i`` at every orientation of ``G`` with the exact limits, so the exact
per-pair test's chain test (:func:`kinematics.workspace.reachable_pairs`: the whole-stroke bound,
which never rejects a feasible pose, then a search over every sample) passes at every ``(P, R)``,
``R in G``. This is the argument of :mod:`kinematics.blocks` with the orientation in place of the
position. (``eps``, 1e-9 of the design's scale, absorbs rounding.)

The samples are arranged in a binary tree (each node split in two halves along the widest of its
tilt-vector ``(theta cos phi, theta sin phi)`` and torsion coordinates, down to single samples);
each node stores as ``R0`` its member whose largest angle to the others is smallest (a node of more
than :data:`CENTRE_EXACT` members: its member nearest their chordal mean, the largest
``tr(R M^T)`` with ``M`` the mean of the members' matrices, in one pass instead of a pass per member:
the certificate holds for any ``R0`` in the node, with the slack measured from it), and ``e_i`` over
its members. A position is decided by a depth-first walk from the root, chain by chain: a
chain certified at a node is not tested below it, a node with a chain left is opened, a single
sample tests its chains left exactly; the walk stops at the first failing test. The answer is
therefore, position by position, the one of testing every sample exactly (the tests compare the
two). A certificate looks only at the samples near the chain's last passing one (a certificate not
found merely opens the node). Only for the plain model (no joint cones, no leg interference): the
caller uses the per-pair test otherwise.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit, prange

from .blocks import rounding_margin
from .design import Design
from .feasibility import _chain_excluded, _feasible_at, chain_points, chain_search
from .kernel_args import kernel_args
from .parallel import kernel_launch
from .progress import CancelToken, Reporter, check
from .workspace import rotation_tables

#: Arc samples either side of the last passing one that a certificate looks at.
WINDOW = 4
#: Positions per kernel launch (cancellation and progress are checked between launches).
CHUNK = 16384
#: Members of a node up to which its centre is the exact minimax member (a pass over the members per
#: member); above, the member nearest their chordal mean (module docstring). The exact rule cost
#: ``m^2`` at a node of ``m``: 34 s holding the whole server at the root of the explorer's 74,425
#: orientations (tilt 30, torsion 60, step 2); the default 15/15/5 set (657) keeps it everywhere.
CENTRE_EXACT = 1024
#: Member visits per step of the tree's build (:func:`_build_steps`; cancellation is checked between
#: steps): about 20-40 ms of one core.
BUILD_WORK = 2_000_000


@njit(cache=True, nogil=True)
def _build_steps(coords, flat, left, right, leaf, centre, lo, hi, perm, st, sp, k, work):
    """The splits of :func:`build_tree`, depth first without recursion, from the stack ``st[:sp + 1]``
    and the next node number ``k`` until the stack is empty or about ``work`` member visits are done
    (a node of ``m <= CENTRE_EXACT`` members counts ``m^2``, its exact centre; a larger one ``20 m``,
    its mean centre and its split):
    per node (preorder) ``left, right, leaf, centre`` and its members ``perm[lo:hi]`` (each node's
    members stay in its range while its descendants reorder them). Returns ``(sp, k)`` (``sp < 0``:
    the tree is complete), so that :func:`_build` checks cancellation between calls. The centre of a
    node of at most :data:`CENTRE_EXACT` members is the member whose largest angle to the others is
    smallest: the angle of ``R_a R_b^T`` is ``arccos((tr(R_a R_b^T) - 1) / 2)``, decreasing in
    ``tr(R_a R_b^T) = flat[a] . flat[b]``, so it is the member whose smallest trace is largest; of a
    larger node, the member whose trace with the members' mean matrix is largest (module docstring).
    Without the GIL: the explorer's other threads keep serving meanwhile."""
    done = 0
    while sp >= 0 and done < work:
        a0, a1, par, side = st[sp, 0], st[sp, 1], st[sp, 2], st[sp, 3]
        sp -= 1
        lo[k], hi[k] = a0, a1
        if par >= 0:
            if side == 0:
                left[par] = k
            else:
                right[par] = k
        members = perm[a0:a1].copy()
        m = members.size
        done += m * m if m <= CENTRE_EXACT else 20 * m
        if m == 1:
            leaf[k] = members[0]
            centre[k] = members[0]
            k += 1
            continue
        best = -np.inf
        c = 0
        if m <= CENTRE_EXACT:
            for j in range(m):
                fj = flat[members[j]]
                worst = np.inf
                for q in range(m):
                    fq = flat[members[q]]
                    t = 0.0
                    for e in range(9):
                        t += fq[e] * fj[e]
                    worst = min(worst, t)
                if worst > best:
                    best = worst
                    c = j
        else:
            mean = np.zeros(9)
            for j in range(m):
                for e in range(9):
                    mean[e] += flat[members[j], e]
            for j in range(m):
                t = 0.0
                for e in range(9):
                    t += flat[members[j], e] * mean[e]
                if t > best:
                    best = t
                    c = j
        centre[k] = members[c]
        axis = 0
        wide = -1.0
        for d in range(3):
            span = coords[members, d].max() - coords[members, d].min()
            if span > wide:
                wide = span
                axis = d
        order = members[np.argsort(coords[members, axis], kind="mergesort")]
        half = m // 2
        ha, hb_ = np.sort(order[:half]), np.sort(order[half:])
        if hb_[0] < ha[0]:
            ha, hb_ = hb_, ha
        perm[a0:a0 + ha.size] = ha
        perm[a0 + ha.size:a1] = hb_
        sp += 1  # the right child below the left one on the stack: preorder, left subtree first
        st[sp, 0], st[sp, 1], st[sp, 2], st[sp, 3] = a0 + ha.size, a1, k, 1
        sp += 1
        st[sp, 0], st[sp, 1], st[sp, 2], st[sp, 3] = a0, a0 + ha.size, k, 0
        k += 1
    return sp, k


def _build(coords: np.ndarray, flat: np.ndarray, cancel: CancelToken = None, work: int | None = None
           ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The tree of :func:`build_tree` for ``n`` samples' ``coords`` (n, 3) and flattened rotations
    ``flat`` (n, 9): ``(left, right, leaf, centre, perm, lo, hi)``, built by :func:`_build_steps` in
    steps of about ``work`` member visits (:data:`BUILD_WORK` by default), with ``cancel`` checked
    before each (the build of the explorer's largest set, 376,809 orientations, takes about 3 s)."""
    work = BUILD_WORK if work is None else int(work)
    n = coords.shape[0]
    size = 2 * n - 1
    left = np.full(size, -1, np.int64)
    right = np.full(size, -1, np.int64)
    leaf = np.full(size, -1, np.int64)
    centre = np.full(size, -1, np.int64)
    lo = np.empty(size, np.int64)
    hi = np.empty(size, np.int64)
    perm = np.arange(n, dtype=np.int64)
    # stack of (lo, hi, parent, side): side 0 = the parent's left child
    st = np.empty((size + 1, 4), np.int64)
    st[0] = (0, n, -1, 0)
    sp, k = 0, 0
    while sp >= 0:
        check(cancel)
        sp, k = _build_steps(coords, flat, left, right, leaf, centre, lo, hi, perm, st, sp, k, work)
    return left, right, leaf, centre, perm, lo, hi


@njit(cache=True, nogil=True)
def _slack_kernel(us, perm, lo, hi, centre, out):
    """:func:`node_slack` node by node: ``out[k, i]`` the largest ``|R u - R0 u|`` over the members
    ``perm[lo[k]:hi[k]]`` and the two points of chain ``i`` (the distance as ``numpy.linalg.norm``
    takes it: the squares summed in order, then the root of the largest)."""
    for k in range(lo.size):
        c = centre[k]
        for i in range(3):
            best = 0.0
            for t in range(lo[k], hi[k]):
                m = perm[t]
                for q in range(2):
                    d = 0.0
                    for e in range(3):
                        x = us[m, i, q, e] - us[c, i, q, e]
                        d += x * x
                    best = max(best, d)
            out[k, i] = math.sqrt(best)


def node_slack(us: np.ndarray, perm: np.ndarray, lo: np.ndarray, hi: np.ndarray, centre: np.ndarray) -> np.ndarray:
    """Per node and chain the slack ``e_i = max_{R in G, u} |R u - R0 u|`` of the module docstring
    (``us``: the rotated platform points (M, 3, 2, 3); node ``k``'s members ``perm[lo[k]:hi[k]]``
    and its ``centre[k]``): (nodes, 3). Compiled, without the GIL and without copying the members'
    points: numpy's expression (the members' and centres' points gathered node by node, 0.97 GB
    each) took 6.4 s and the process's peak memory to 3.2 GB at the explorer's largest orientation
    sets (352,557 orientations), unstoppable; this takes 0.23 s there (peak 0.56 GB)."""
    out = np.zeros((len(lo), 3))
    if len(lo):
        _slack_kernel(np.ascontiguousarray(us, dtype=np.float64), np.ascontiguousarray(perm, dtype=np.int64),
                      np.ascontiguousarray(lo, dtype=np.int64), np.ascontiguousarray(hi, dtype=np.int64),
                      np.ascontiguousarray(centre, dtype=np.int64), out)
    return out


def build_tree(samples: np.ndarray, rots: np.ndarray, first: int = 0, cancel: CancelToken = None
               ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The tree of the module docstring over ``samples[first:]`` (M, 3: azimuth, tilt, torsion in
    degrees) with rotations ``rots[first:]`` (M, 3, 3), numbered as the whole set. Returns per node
    ``(left, right, sample, centre)``: children (-1 for a single sample), the sample of a leaf (-1
    otherwise), the centre sample; and ``(perm, lo, hi)``: node ``k``'s members are
    ``perm[lo[k]:hi[k]]``. Node 0 is the root. Children are ordered as the samples (hardest first).
    ``cancel`` is checked between the build's steps (:func:`_build`)."""
    samples, rots = samples[first:], rots[first:]
    az, th = np.radians(samples[:, 0]), samples[:, 1]
    coords = np.stack([th * np.cos(az), th * np.sin(az), samples[:, 2]], axis=1)
    if not samples.shape[0]:
        z = np.zeros(0, np.int64)
        return z, z, z, z, z, z, z
    left, right, leaf, centre, perm, lo, hi = _build(np.ascontiguousarray(coords),
                                                     np.ascontiguousarray(rots.reshape(-1, 9)), cancel)
    if first:
        leaf = np.where(leaf >= 0, leaf + first, -1)
        centre = centre + first
        perm = perm + first
    return left, right, leaf, centre, perm, lo, hi


@njit(cache=True)
def _certified(px, py, pz, u, i, cos_t, sin_t, arc, hb, rho_lo, rho_hi, lo2, hi2, jc, hint):
    """The certificate of the module docstring for chain ``i`` at ``P`` with the rotated platform
    points ``u`` of ``R0`` and the tightened limits ``lo2 = (l_min + e)^2``, ``hi2 = (l_max - e)^2``,
    looking for a sample within :data:`WINDOW` of ``hint[i]`` (the chain's last passing sample,
    updated): a certificate not found only opens the node."""
    n = cos_t.shape[1]
    b1x, b1y, b1z, b2x, b2y, b2z = chain_points(px, py, pz, u, i)
    if _chain_excluded(b1x, b1y, b1z, b2x, b2y, b2z, hb, arc[i], rho_lo, rho_hi, lo2, hi2):
        return False
    for step in range(2 * WINDOW + 1):
        off = (step + 1) // 2
        k = hint[i] + off if step % 2 == 1 else hint[i] - off
        if k < 0 or k >= n:
            continue
        if _feasible_at(b1x, b1y, b1z, b2x, b2y, b2z, cos_t[i, k], sin_t[i, k], hb, rho_lo, rho_hi, lo2, hi2,
                        jc[i], 0.0):
            hint[i] = k
            return True
    return False


@njit(cache=True)
def _exact(px, py, pz, u, i, cos_t, sin_t, arc, hb, rho_lo, rho_hi, lmin2, lmax2, jc, hint):
    """The per-pair test of :func:`kinematics.workspace._pairs_kernel` for chain ``i`` at one
    orientation ("some arc sample passes"), trying the chain's last passing sample ``hint[i]`` first
    (the same answer: the whole-stroke bound never rejects a feasible pose)."""
    b1x, b1y, b1z, b2x, b2y, b2z = chain_points(px, py, pz, u, i)
    k = hint[i]
    if _feasible_at(b1x, b1y, b1z, b2x, b2y, b2z, cos_t[i, k], sin_t[i, k], hb, rho_lo, rho_hi, lmin2, lmax2, jc[i],
                    0.0):
        return True
    if _chain_excluded(b1x, b1y, b1z, b2x, b2y, b2z, hb, arc[i], rho_lo, rho_hi, lmin2, lmax2):
        return False
    k = chain_search(b1x, b1y, b1z, b2x, b2y, b2z, cos_t[i], sin_t[i], hb, rho_lo, rho_hi, lmin2, lmax2, jc[i],
                     cos_t.shape[1] // 2)
    if k < 0:
        return False
    hint[i] = k
    return True


@njit(parallel=True, cache=True, nogil=True)
def _tree_kernel(points, us, jcs, first, left, right, leaf, centre, lo2, hi2, cos_t, sin_t, arc, hb, rho_lo,
                 rho_hi, lmin2, lmax2, out):
    """``out[p]``: ``points[p]`` passes the exact test at every sample (the tree walk of the module
    docstring, chain by chain: a chain certified at a node is not tested below it), after the
    samples ``0 .. first - 1`` tested one by one; ``lo2``/``hi2`` (nodes, 3): each chain's tightened
    limits squared (``hi2 < 0``: no certificate)."""
    n_eta = cos_t.shape[1]
    for p in prange(points.shape[0]):
        px, py, pz = points[p, 0], points[p, 1], points[p, 2]
        stack = np.empty(128, np.int64)
        done = np.empty(128, np.int64)
        hint = np.full(3, n_eta // 2, np.int64)
        ok = True
        for m in range(first):
            for i in range(3):
                if not _exact(px, py, pz, us[m], i, cos_t, sin_t, arc, hb, rho_lo, rho_hi, lmin2, lmax2, jcs[m], hint):
                    ok = False
                    break
            if not ok:
                break
        top = 0 if left.shape[0] else -1
        stack[0] = 0
        done[0] = 0
        while top >= 0 and ok:
            nd = stack[top]
            bits = done[top]
            top -= 1
            m = leaf[nd]
            for i in range(3):
                if (bits >> i) & 1:
                    continue
                if m >= 0:
                    if not _exact(px, py, pz, us[m], i, cos_t, sin_t, arc, hb, rho_lo, rho_hi, lmin2, lmax2, jcs[m],
                                  hint):
                        ok = False
                        break
                elif hi2[nd, i] >= 0.0 and _certified(px, py, pz, us[centre[nd]], i, cos_t, sin_t, arc, hb, rho_lo,
                                                      rho_hi, lo2[nd, i], hi2[nd, i], jcs[centre[nd]], hint):
                    bits |= 1 << i
            if m < 0 and bits != 7:
                top += 1
                stack[top] = right[nd]
                done[top] = bits
                top += 1
                stack[top] = left[nd]
                done[top] = bits
        out[p] = ok


def reachable_at_all(design: Design, points: np.ndarray, samples: np.ndarray, rotations: np.ndarray, n_eta: int,
                     first: int = 0, progress: Reporter | None = None, cancel: CancelToken = None) -> np.ndarray:
    """Whether each of ``points`` (N, 3) passes the exact per-pair test at every rotation of
    ``rotations`` (M, 3, 3; ``samples`` their (azimuth, tilt, torsion) rows), plain model only
    (module docstring): bool (N,). The first ``first`` samples (the hardest: most positions that
    fail, fail one of them) are tested one by one before the tree of the others."""
    from .joints import Joints

    pts = np.ascontiguousarray(np.asarray(points, dtype=np.float64).reshape(-1, 3))
    rots = np.ascontiguousarray(np.asarray(rotations, dtype=np.float64).reshape(-1, 3, 3))
    out = np.zeros(pts.shape[0], np.bool_)
    if not pts.shape[0]:
        return out
    if not rots.shape[0]:
        out[:] = True
        return out
    _u, cos_t, sin_t, arc, hb, rho_lo, rho_hi, lmin2, lmax2, _ = kernel_args(design, np.eye(3), n_eta)
    us, jcs = rotation_tables(design, rots, Joints())
    first = min(int(first), rots.shape[0])
    left, right, leaf, centre, perm, lo, hi = build_tree(samples, rots, first, cancel)
    lmin, lmax = math.sqrt(lmin2), math.sqrt(lmax2)
    eps = rounding_margin(lmax, (pts[:, 0], pts[:, 1], pts[:, 2]))
    e = node_slack(us, perm, lo, hi, centre) + eps
    lo2 = (lmin + e) ** 2
    hi2 = np.where(lmin + e <= lmax - e, (lmax - e) ** 2, -1.0)
    hi2[leaf >= 0] = -1.0
    for s in range(0, pts.shape[0], CHUNK):
        check(cancel)
        sl = slice(s, min(pts.shape[0], s + CHUNK))
        with kernel_launch(sl.stop - sl.start):
            _tree_kernel(pts[sl], us, jcs, first, left, right, leaf, centre, lo2, hi2, cos_t, sin_t, arc, hb, rho_lo,
                         rho_hi, lmin2, lmax2, out[sl])
        if progress is not None:
            progress(sl.stop / pts.shape[0], "total-orientation workspace")
    return out
