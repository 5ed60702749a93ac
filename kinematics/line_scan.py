"""Reachability of every (point, rotation) pair when the points lie along a line, coarse to fine.

Definition: ``reachable_along(design, points, rotations)[p, m]`` is exactly
:func:`kinematics.workspace.reachable_pairs` (the per-chain test of :mod:`kinematics.feasibility`
at position ``points[p]`` and rotation ``rotations[m]``: every chain passes the conservative
whole-stroke bound and some arc sample admits a rail coordinate with both legs in ``[l_min,
l_max]`` and inside the joint cones; leg interference as a final mask). It is tested pair by pair
against that function. It only spends less work when consecutive points are close, as on the
orientation scan's symmetry lines (:mod:`kinematics.orientation`); it is correct for any points.

Why the result is identical
---------------------------
For each rotation the points are walked in order, in runs (blocks) of at most :data:`TOP_RUN`
consecutive points, split in halves while undecided:

* A run with centre ``Pc`` (the mean of its first and last point) and radius ``delta = max_p |P_p -
  Pc|`` over its points is classified chain by chain with the Lipschitz lemma of
  :mod:`kinematics.blocks` (for a fixed rotation and carriage pose each leg length, and each joint
  cone function with the factor ``1 + k``, moves by at most ``|P - Pc|``), at ``e = delta + eps``
  (``eps`` = 1e-9 of the scene's scale absorbs rounding): if at ``Pc`` no arc sample admits a rail
  coordinate with the limits relaxed to ``[l_min - e, l_max + e]`` (the whole-stroke bound with
  relaxed limits first) the chain fails at every point of the run; if one sample admits one with
  the limits tightened to ``[l_min + e, l_max - e]`` the same carriage pose serves every point with
  a margin, so the exact test succeeds there (:func:`kinematics.blocks.decide_chain`, which also
  skips the sub-arcs the whole-stroke bound rejects). A chain failing decides the whole run unreachable;
  all chains succeeding decide it reachable; otherwise the run is halved and the halves inherit the
  chains already proven.
* A single point is decided with the exact test itself: the whole-stroke bound, then the arc
  samples searched outward from the sample that served the previous point of the walk (a warm
  start, as in the dense workspace kernel), and the chain that failed last is tested first. Order
  and start do not change the answer: the search visits every sample before reporting failure.

Cost: the pairs far from the boundary of a line's region are decided a run at a time, the others
at about one arc sample per chain; one parallel launch over the rotations (dynamic chunks, see
:mod:`kinematics.parallel`).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit, prange

from .blocks import FAIL, OK, UNKNOWN, decide_chain, sub_arcs
from .design import Design
from .feasibility import ChainTables, _chain_excluded, chain_points, chain_search, default_n_eta
from .geometry import platform_points_local
from .interference import interference_free
from .joints import Joints
from .parallel import kernel_launch
from .workspace import rotation_tables

__all__ = ["reachable_along", "TOP_RUN"]

#: Longest run of consecutive points classified at once (halved while undecided). Measured on the
#: default orientation scan: 4 and 8 are the fastest (0.74 and 0.80 of 16's time, single thread).
TOP_RUN = 4


@njit(parallel=True, cache=True, nogil=True)
def _along_kernel(points, us, cos_t, sin_t, arc, seg_k, seg_arc, hb, rho_lo, rho_hi, lmin2, lmax2, jcs, eps, top_run,
                  out):
    """``out[m, p]``: reachability of ``points[p]`` at the rotation whose rotated platform points are
    ``us[m]`` (shape (M, 3, 2, 3)) and joint-cone table ``jcs[m]`` (M, 3, 2, 8)."""
    n_eta = cos_t.shape[1]
    n_p = points.shape[0]
    lmin = math.sqrt(lmin2)
    lmax = math.sqrt(lmax2)
    for m in prange(us.shape[0]):
        u = us[m]
        jc = jcs[m]
        start = np.empty(3, np.int64)
        for i in range(3):
            start[i] = n_eta // 2
        win = np.empty(3, np.int64)  # decide_chain's (hint, lo, hi): every sample, from start
        first = 0
        stack = np.empty((64, 5), np.int64)  # (first point, points, state of chain 0, 1, 2)
        top = 0
        nxt = 0
        while nxt < n_p or top > 0:
            if top == 0:
                nb = min(top_run, n_p - nxt)
                stack[0, 0] = nxt
                stack[0, 1] = nb
                stack[0, 2] = UNKNOWN
                stack[0, 3] = UNKNOWN
                stack[0, 4] = UNKNOWN
                top = 1
                nxt += nb
            top -= 1
            a = stack[top, 0]
            nb = stack[top, 1]
            s0 = stack[top, 2]
            s1 = stack[top, 3]
            s2 = stack[top, 4]
            if nb == 1:  # the exact test, skipping the chains the run proved
                ok = True
                for kk in range(3):
                    i = (first + kk) % 3
                    si = s0 if i == 0 else (s1 if i == 1 else s2)
                    if si == OK:
                        continue
                    b1x, b1y, b1z, b2x, b2y, b2z = chain_points(points[a, 0], points[a, 1], points[a, 2], u, i)
                    k = -1
                    if not _chain_excluded(b1x, b1y, b1z, b2x, b2y, b2z, hb, arc[i], rho_lo, rho_hi, lmin2, lmax2):
                        k = chain_search(b1x, b1y, b1z, b2x, b2y, b2z, cos_t[i], sin_t[i], hb, rho_lo, rho_hi,
                                         lmin2, lmax2, jc[i], start[i])
                    if k < 0:
                        ok = False
                        first = i
                        break
                    start[i] = k
                out[m, a] = ok
                continue
            b = a + nb - 1
            cx = 0.5 * (points[a, 0] + points[b, 0])
            cy = 0.5 * (points[a, 1] + points[b, 1])
            cz = 0.5 * (points[a, 2] + points[b, 2])
            r2 = 0.0
            for q in range(a, b + 1):
                dx = points[q, 0] - cx
                dy = points[q, 1] - cy
                dz = points[q, 2] - cz
                r2 = max(r2, dx * dx + dy * dy + dz * dz)
            e = math.sqrt(r2) + eps
            fail = False
            all_ok = True
            for kk in range(3):
                i = (first + kk) % 3
                si = s0 if i == 0 else (s1 if i == 1 else s2)
                if si != UNKNOWN:
                    continue
                win[0] = start[i]
                win[1] = 0
                win[2] = n_eta - 1
                si = decide_chain(cx, cy, cz, u, i, cos_t, sin_t, arc, seg_k, seg_arc, hb, rho_lo, rho_hi,
                                  lmin, lmax, jc, e + eps, e, e, e, True, win)
                if si == FAIL:
                    fail = True
                    first = i
                    break
                if si == OK:
                    start[i] = win[0]
                else:
                    all_ok = False
                if i == 0:
                    s0 = si
                elif i == 1:
                    s1 = si
                else:
                    s2 = si
            if fail or all_ok:
                for q in range(a, b + 1):
                    out[m, q] = not fail
                continue
            h = (nb + 1) // 2  # halves: the first is popped (walked) first
            stack[top, 0] = a + h
            stack[top, 1] = nb - h
            stack[top, 2] = s0
            stack[top, 3] = s1
            stack[top, 4] = s2
            stack[top + 1, 0] = a
            stack[top + 1, 1] = h
            stack[top + 1, 2] = s0
            stack[top + 1, 3] = s1
            stack[top + 1, 4] = s2
            top += 2


def reachable_along(design: Design, points: np.ndarray, rotations: np.ndarray, eta_step: float = 0.5,
                    joints: Joints | None = None) -> np.ndarray:
    """Whether each point is reachable at each orientation: bool array (N, M) for ``points`` (N, 3)
    and rotation matrices ``rotations`` (M, 3, 3), identical to
    :func:`kinematics.workspace.reachable_pairs` (module docstring); fast when consecutive points
    are close (points along a line, in order)."""
    pts = np.ascontiguousarray(np.asarray(points, dtype=np.float64).reshape(-1, 3))
    rots = np.asarray(rotations, dtype=np.float64).reshape(-1, 3, 3)
    n_eta = default_n_eta(design, eta_step)
    tab = ChainTables(design, n_eta)
    local = platform_points_local(design)
    jn = joints or Joints()
    us, jcs = rotation_tables(design, rots, jn)
    out = np.zeros((rots.shape[0], pts.shape[0]), np.bool_)
    if out.size:
        scale = max(1.0, design.l_max, design.r, float(np.abs(pts).max()) + float(np.abs(local).max()))
        seg_k, seg_arc = sub_arcs(tab.cos_t, tab.sin_t)
        with kernel_launch(rots.shape[0]):
            _along_kernel(pts, us, tab.cos_t, tab.sin_t, tab.arc, seg_k, seg_arc, tab.hb, tab.rho_lo, tab.rho_hi,
                          tab.lmin2, tab.lmax2, jcs, 1e-9 * scale, TOP_RUN, out)
    res = np.ascontiguousarray(out.T)
    if res.size and jn.min_distance > 0.0 and res.any():
        res &= interference_free(design, jn, pts, rots, n_eta, where=res)
    return res
