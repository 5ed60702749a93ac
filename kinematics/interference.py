"""Leg interference: do the six legs clear each other in SOME carriage configuration?

Each leg is a capsule around its axis segment ``D B`` (U joint to S joint) of diameter
``leg_diameter``; two legs interfere when their axes are closer than ``d_min = leg_diameter +
clearance`` (:func:`segment_distance`, the closed-form distance of two segments). The constraint
couples the chains (legs of different chains can meet), so reachability is no longer the
intersection of three independent chain sets. The engine decides it as follows (our documented
definition):

1. The per-chain test of :mod:`kinematics.feasibility` (strokes and joint cones) runs first; a pose
   that fails it is unreachable.
2. **Witnesses.** For each chain, the arc samples ``k = 0 .. n - 1`` are scanned outward from the
   stroke's middle ``m = n // 2``: ``m, m + 1, m - 1, m + 2, ...`` (:func:`scan_sample`) when the
   platform centre has ``y >= 0``, and each ``k`` of that order replaced by ``n - 1 - k`` when ``y <
   0``. At each sample that serves the chain, the feasible ``rho`` set (at most four intervals,
   :func:`kinematics.feasibility.feasible_rho`) is probed at each interval's ends and middle, and
   the first probe at which the chain's own two legs clear each other is that sample's witness
   carriage pose (one per sample).

   Why the order turns with the sign of ``y``: the mirror ``y -> -y`` maps chain 1 onto itself and
   chains 2 and 3 onto each other, each arc sample ``k`` onto ``n - 1 - k`` of its image (the
   centered arc range). With one order for every pose, a pose and its mirror image scanned their
   samples in mirrored orders, found first witnesses that are not mirror images where two samples
   at the same distance from the middle both serve, and could get different answers: 6,400 of the
   default design's voxels at h = 1 (diameter 10; 3,200 mirror pairs, 0.2 % of its free voxels)
   had a mirror image with the other answer. With the order turned, the search at the mirror image
   of a pose is the mirror image of the search at the pose (the pair tests and the spread below do
   not depend on the chains' order), so a mirror-symmetric design at a mirror-symmetric orientation
   gets a mirror-symmetric answer, and the grid engine computes half of it
   (:mod:`kinematics.interference_blocks`).
3. **Coupling.** The pose is reachable when one witness per chain makes every pair of legs of
   different chains clear. The first witnesses (nearest the stroke middle) are tried first; if they
   collide, up to :data:`SPREAD` witnesses per chain spread evenly over the stroke are combined
   (at most ``SPREAD^3`` combinations, 12 segment distances each).

Every pose reported reachable comes with a concrete carriage configuration that satisfies every
limit and every clearance, so the engine **never reports a pose reachable that is not**; it may
miss poses whose clearing configurations fall between the probes (the error is one-sided, like the
arc sampling). Cost: the filter runs only on poses that pass step 1; most pass with their first
witnesses (about 15 segment distances per pose).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit, prange

from .design import Design
from .feasibility import (
    _leg_frames,
    _leg_intervals,
    chain_excluded_at,
    chain_points,
    cones_set,
    feasible_rho,
    piece_meet,
)
from .geometry import platform_points_local
from .joints import Joints, cone_table
from .parallel import KERNEL_LOCK

__all__ = ["segment_distance", "segment_closest", "interference_free", "clear_configuration", "SPREAD"]

#: Witnesses per chain combined when the first ones collide.
SPREAD = 4


@njit(cache=True, forceinline=True)
def segment_distance(ax, ay, az, bx, by, bz, cx, cy, cz, dx, dy, dz):
    """Distance between the segments ``[A, B]`` and ``[C, D]`` (closest points by clamped
    parameters, Ericson, *Real-Time Collision Detection*, sec. 5.1.9)."""
    s, t = segment_closest(ax, ay, az, bx, by, bz, cx, cy, cz, dx, dy, dz)
    d1x, d1y, d1z = bx - ax, by - ay, bz - az
    d2x, d2y, d2z = dx - cx, dy - cy, dz - cz
    px, py, pz = ax + d1x * s - (cx + d2x * t), ay + d1y * s - (cy + d2y * t), az + d1z * s - (cz + d2z * t)
    return math.sqrt(px * px + py * py + pz * pz)


@njit(cache=True, inline="always")
def segment_closest(ax, ay, az, bx, by, bz, cx, cy, cz, dx, dy, dz):
    """Parameters ``(s, t)`` of the closest points ``A + s (B - A)`` and ``C + t (D - C)`` of the
    segments ``[A, B]`` and ``[C, D]`` (:func:`segment_distance`)."""
    d1x, d1y, d1z = bx - ax, by - ay, bz - az
    d2x, d2y, d2z = dx - cx, dy - cy, dz - cz
    rx, ry, rz = ax - cx, ay - cy, az - cz
    a = d1x * d1x + d1y * d1y + d1z * d1z
    e = d2x * d2x + d2y * d2y + d2z * d2z
    f = d2x * rx + d2y * ry + d2z * rz
    tiny = 1e-300
    if a <= tiny and e <= tiny:
        s = 0.0
        t = 0.0
    elif a <= tiny:
        s = 0.0
        t = min(max(f / e, 0.0), 1.0)
    else:
        c = d1x * rx + d1y * ry + d1z * rz
        if e <= tiny:
            t = 0.0
            s = min(max(-c / a, 0.0), 1.0)
        else:
            b = d1x * d2x + d1y * d2y + d1z * d2z
            denom = a * e - b * b
            s = min(max((b * f - c * e) / denom, 0.0), 1.0) if denom > 0.0 else 0.0
            t = (b * s + f) / e
            if t < 0.0:
                t = 0.0
                s = min(max(-c / a, 0.0), 1.0)
            elif t > 1.0:
                t = 1.0
                s = min(max((b - c) / a, 0.0), 1.0)
    return s, t


@njit(cache=True)
def pose_scratch(n):
    """The scratch one :func:`_pose_clear` call writes, for ``n`` arc samples: ``(wit (3, n, 6), bp
    (3, 2, 3), pieces (4, 2), pick (3, SPREAD), cnt (2, 3))``. A caller that decides many poses
    allocates it once (each allocation costs a call to the allocator and atomic reference counts)."""
    return (np.empty((3, n, 6)), np.empty((3, 2, 3)), np.empty((4, 2)), np.empty((3, SPREAD), np.int64),
            np.empty((2, 3), np.int64))


@njit(cache=True, inline="always")
def _probe_clears(rho, c, s, hb, b1x, b1y, b1z, b2x, b2y, b2z, dmin):
    """Whether the two legs of the carriage at ``rho`` on the rail ``(c, s)`` are at least ``dmin``
    apart (S joints ``B_1``, ``B_2``)."""
    x1, y1 = rho * c - hb * s, rho * s + hb * c
    x2, y2 = rho * c + hb * s, rho * s - hb * c
    return segment_distance(x1, y1, 0.0, b1x, b1y, b1z, x2, y2, 0.0, b2x, b2y, b2z) >= dmin


@njit(cache=True, inline="always")
def _piece_witness(lo, hi, c, s, hb, b1x, b1y, b1z, b2x, b2y, b2z, dmin):
    """The first probe of one feasible interval ``[lo, hi]`` of ``rho`` at which the carriage's own two
    legs clear each other (module doc, step 2: its ends, then its middle), or NaN when none does."""
    if _probe_clears(lo, c, s, hb, b1x, b1y, b1z, b2x, b2y, b2z, dmin):
        return lo
    if _probe_clears(hi, c, s, hb, b1x, b1y, b1z, b2x, b2y, b2z, dmin):
        return hi
    mid = 0.5 * (lo + hi)
    if _probe_clears(mid, c, s, hb, b1x, b1y, b1z, b2x, b2y, b2z, dmin):
        return mid
    return math.nan


@njit(cache=True, forceinline=True)
def _sample_witness(b1x, b1y, b1z, b2x, b2y, b2z, c, s, hb, rho_lo, rho_hi, lmin2, lmax2, jci, dmin, pieces):
    """The witness ``rho`` of one arc sample (module doc, step 2): the first probe, interval by interval
    of :func:`kinematics.feasibility.feasible_rho` (cut by the joint cones of ``jci``), at which the
    carriage's own legs clear; NaN when the sample does not serve the chain or no probe clears.
    ``pieces`` (4, 2): scratch."""
    npc = feasible_rho(b1x, b1y, b1z, b2x, b2y, b2z, c, s, hb, rho_lo, rho_hi, lmin2, lmax2, jci, pieces)
    for pc in range(npc):
        rho = _piece_witness(pieces[pc, 0], pieces[pc, 1], c, s, hb, b1x, b1y, b1z, b2x, b2y, b2z, dmin)
        if rho == rho:
            return rho
    return math.nan


@njit(cache=True, forceinline=True)
def _plain_witness(b1x, b1y, b1z, b2x, b2y, b2z, c, s, hb, rho_lo, rho_hi, lmin2, lmax2, dmin):
    """:func:`_sample_witness` for a chain without joint cones, the same number (tested): the same
    intervals in the same order (both legs' (F2) sets met on the rail by ``piece_meet``, as
    ``feasible_rho`` meets them), from numbers only. No array argument and no scratch: the witness
    search of a voxel near the workspace's boundary visits dozens of samples that do not serve, and
    a call with arrays (two for ``feasible_rho``) costs more than their test."""
    p1, _, q1, p2, _, q2 = _leg_frames(b1x, b1y, b1z, b2x, b2y, b2z, c, s, hb)
    n1, a0, a1, a2, a3 = _leg_intervals(p1, q1, lmin2, lmax2)
    if n1 == 0:
        return math.nan
    n2, c0, c1, c2, c3 = _leg_intervals(p2, q2, lmin2, lmax2)
    if n2 == 0:
        return math.nan
    for ua in range(n1):
        for ub in range(n2):
            lo, hi = piece_meet(ua, ub, a0, a1, a2, a3, c0, c1, c2, c3, rho_lo, rho_hi)
            if lo <= hi:
                rho = _piece_witness(lo, hi, c, s, hb, b1x, b1y, b1z, b2x, b2y, b2z, dmin)
                if rho == rho:
                    return rho
    return math.nan


@njit(cache=True, inline="always")
def scan_sample(step, n, flip):
    """The arc sample the witness search visits at ``step`` (module doc, step 2): outward from the
    middle ``n // 2``, the upper side first, each sample ``k`` replaced by ``n - 1 - k`` with ``flip``
    (a platform centre with ``y < 0``); -1 for a step past an end of the stroke."""
    mid = n // 2
    off = (step + 1) // 2
    k = mid + off if step % 2 == 1 else mid - off
    if k < 0 or k >= n:
        return -1
    return n - 1 - k if flip else k


@njit(cache=True, forceinline=True)
def _witnesses(b1x, b1y, b1z, b2x, b2y, b2z, cos_t, sin_t, i, hb, rho_lo, rho_hi, lmin2, lmax2, jc, dmin,
               cap, wit, skip, sb, pieces, flip, start, found):
    """Up to ``cap`` witness carriage poses of chain ``i`` (module doc, step 2) as the two U joints
    ``(D1, D2)`` in ``wit[i, w] = (x1, y1, z1, x2, y2, z2)``, scanning from step ``start`` on with the
    ``found`` witnesses already in ``wit[i]`` kept (0, 0: the whole scan; a later start takes a scan
    up where an earlier one stopped). Returns ``(count, step)``: the witnesses found in all and the
    step after the last one visited. Samples
    ``k`` with ``skip[sb, i, k]`` are passed over: the caller knows they are no witness (all False:
    every sample is tried). The tables (``cos_t``, ``sin_t``, ``skip`` (m, 3, n), ``jc``) are read in
    place: a view costs two atomic reference counts, on tables every thread shares. ``pieces`` (4,
    2): scratch. A chain without joint cones is tested from numbers only (:func:`_plain_witness`).
    ``flip``: the order of a platform centre with ``y < 0`` (:func:`scan_sample`)."""
    n = cos_t.shape[1]
    jci = jc[i]
    plain = not cones_set(jci)
    cnt = found
    for step in range(start, n):
        k = scan_sample(step, n, flip)
        if k < 0 or skip[sb, i, k]:
            continue
        c, s = cos_t[i, k], sin_t[i, k]
        if plain:
            rho = _plain_witness(b1x, b1y, b1z, b2x, b2y, b2z, c, s, hb, rho_lo, rho_hi, lmin2, lmax2, dmin)
        else:
            rho = _sample_witness(b1x, b1y, b1z, b2x, b2y, b2z, c, s, hb, rho_lo, rho_hi, lmin2, lmax2, jci, dmin,
                                  pieces)
        if rho != rho:
            continue
        wit[i, cnt, 0], wit[i, cnt, 1], wit[i, cnt, 2] = rho * c - hb * s, rho * s + hb * c, 0.0
        wit[i, cnt, 3], wit[i, cnt, 4], wit[i, cnt, 5] = rho * c + hb * s, rho * s - hb * c, 0.0
        cnt += 1
        if cnt >= cap:
            return cnt, step + 1
    return cnt, n


@njit(cache=True, inline="always")
def _clear(bp, wit, i, ia, j, ib, dmin):
    """Whether every leg of chain ``i`` (witness ``wit[i, ia]``) clears every leg of chain ``j``
    (witness ``wit[j, ib]``)."""
    for la in range(2):
        for lb in range(2):
            if segment_distance(wit[i, ia, 3 * la], wit[i, ia, 3 * la + 1], wit[i, ia, 3 * la + 2],
                                bp[i, la, 0], bp[i, la, 1], bp[i, la, 2],
                                wit[j, ib, 3 * lb], wit[j, ib, 3 * lb + 1], wit[j, ib, 3 * lb + 2],
                                bp[j, lb, 0], bp[j, lb, 1], bp[j, lb, 2]) < dmin:
                return False
    return True


@njit(cache=True, forceinline=True)
def _pose_clear(px, py, pz, u, cos_t, sin_t, arc, hb, rho_lo, rho_hi, lmin2, lmax2, jc, dmin, sel, skip, sb,
                wit, bp, pieces, pick, cnt, screen):
    """Module doc, steps 2-3, for one platform pose (``u``: its rotated platform points); the chosen
    U joints are written to ``sel`` (3, 6) when it returns True. ``skip[sb]`` (3, n): arc samples
    known to be no witness of their chain at this pose, passed over (:func:`_witnesses`; all False:
    none). ``wit, bp, pieces, pick, cnt``: scratch from :func:`pose_scratch`. The samples are scanned
    in the order of the sign of ``py`` (module doc, step 2). ``screen``: first reject a chain that the
    whole-stroke bound excludes (:func:`kinematics.feasibility.chain_excluded_at`), a shortcut for
    poses a chain does not reach; the answer is the same without it (no sample of an excluded chain
    serves, so it has no witness), and a caller whose poses every chain reaches passes False.

    Where the first witnesses collide, each chain's list of witnesses goes on from its first one (the
    scan is taken up where it stopped), and the lists of the two chains whose first witnesses collide
    first come first: when no pick of one clears any pick of the other, no combination clears, so the
    answer is False without the third chain's list. Otherwise the combinations are tried in their
    order, each pair of picks tested once (a memo). The answer and the configuration are those of
    every combination tried in order (tested against a plain reading of the definition)."""
    flip = py < 0.0
    for i in range(3):
        b1x, b1y, b1z, b2x, b2y, b2z = chain_points(px, py, pz, u, i)
        bp[i, 0, 0], bp[i, 0, 1], bp[i, 0, 2] = b1x, b1y, b1z
        bp[i, 1, 0], bp[i, 1, 1], bp[i, 1, 2] = b2x, b2y, b2z
        if screen and chain_excluded_at(b1x, b1y, b1z, b2x, b2y, b2z, hb, arc, i, rho_lo, rho_hi, lmin2, lmax2):
            return False
        # cnt[1, i]: the step after the first witness, where the spread's scan takes up
        cnt[0, i], cnt[1, i] = _witnesses(b1x, b1y, b1z, b2x, b2y, b2z, cos_t, sin_t, i, hb, rho_lo, rho_hi,
                                          lmin2, lmax2, jc, dmin, 1, wit, skip, sb, pieces, flip, 0, 0)
        if cnt[0, i] == 0:
            return False
    # the first pair of chains (in the order tested) whose first witnesses collide: (a, b); c the third
    if not _clear(bp, wit, 0, 0, 1, 0, dmin):
        a, b, c = 0, 1, 2
    elif not _clear(bp, wit, 1, 0, 2, 0, dmin):
        a, b, c = 1, 2, 0
    elif not _clear(bp, wit, 0, 0, 2, 0, dmin):
        a, b, c = 0, 2, 1
    else:
        for i in range(3):
            for t in range(6):
                sel[i, t] = wit[i, 0, t]
        return True
    # the first witnesses collide: combine witnesses spread over the stroke. memo[p, q, r] for the pairs
    # p = 0: chains (1, 2), 1: (2, 3), 2: (1, 3), picks q and r: -1 not yet, 0 they collide, 1 they clear
    memo = np.full((3, SPREAD, SPREAD), -1, np.int8)
    _spread_picks(bp, a, cos_t, sin_t, hb, rho_lo, rho_hi, lmin2, lmax2, jc, dmin, wit, skip, sb, pieces, flip, pick,
                  cnt)
    _spread_picks(bp, b, cos_t, sin_t, hb, rho_lo, rho_hi, lmin2, lmax2, jc, dmin, wit, skip, sb, pieces, flip, pick,
                  cnt)
    pair = 0 if c == 2 else (1 if c == 0 else 2)
    some = False
    for qa in range(cnt[1, a]):
        for qb in range(cnt[1, b]):
            memo[pair, qa, qb] = 1 if _clear(bp, wit, a, pick[a, qa], b, pick[b, qb], dmin) else 0
            if memo[pair, qa, qb] == 1:
                some = True
                break
        if some:
            break
    if not some:
        return False
    _spread_picks(bp, c, cos_t, sin_t, hb, rho_lo, rho_hi, lmin2, lmax2, jc, dmin, wit, skip, sb, pieces, flip, pick,
                  cnt)
    for q0 in range(cnt[1, 0]):
        for q1 in range(cnt[1, 1]):
            if memo[0, q0, q1] < 0:
                memo[0, q0, q1] = 1 if _clear(bp, wit, 0, pick[0, q0], 1, pick[1, q1], dmin) else 0
            if memo[0, q0, q1] == 0:
                continue
            for q2 in range(cnt[1, 2]):
                if memo[1, q1, q2] < 0:
                    memo[1, q1, q2] = 1 if _clear(bp, wit, 1, pick[1, q1], 2, pick[2, q2], dmin) else 0
                if memo[1, q1, q2] == 0:
                    continue
                if memo[2, q0, q2] < 0:
                    memo[2, q0, q2] = 1 if _clear(bp, wit, 0, pick[0, q0], 2, pick[2, q2], dmin) else 0
                if memo[2, q0, q2] == 1:
                    for t in range(6):
                        sel[0, t] = wit[0, pick[0, q0], t]
                        sel[1, t] = wit[1, pick[1, q1], t]
                        sel[2, t] = wit[2, pick[2, q2], t]
                    return True
    return False


@njit(cache=True)
def _spread_picks(bp, i, cos_t, sin_t, hb, rho_lo, rho_hi, lmin2, lmax2, jc, dmin, wit, skip, sb, pieces, flip, pick,
                  cnt):
    """Chain ``i``'s whole list of witnesses (module doc, step 3: its scan taken up at step ``cnt[1, i]``,
    after its first witness; its S joints in ``bp[i]``) and its picks: ``cnt[0, i]`` witnesses,
    ``cnt[1, i]`` picks spread evenly over them in ``pick[i]``."""
    n = cos_t.shape[1]
    cnt[0, i] = _witnesses(bp[i, 0, 0], bp[i, 0, 1], bp[i, 0, 2], bp[i, 1, 0], bp[i, 1, 1], bp[i, 1, 2], cos_t, sin_t,
                           i, hb, rho_lo, rho_hi, lmin2, lmax2, jc, dmin, n, wit, skip, sb, pieces, flip, cnt[1, i],
                           1)[0]
    m = min(SPREAD, cnt[0, i])
    cnt[1, i] = m
    for q in range(m):
        pick[i, q] = 0 if m == 1 else int(round(q * (cnt[0, i] - 1) / (m - 1)))


@njit(parallel=True, cache=True, nogil=True)
def _clear_kernel(points, us, jcs, cos_t, sin_t, arc, hb, rho_lo, rho_hi, lmin2, lmax2, dmin, where, out):
    n_m = us.shape[0]
    skip = np.zeros((1, 3, cos_t.shape[1]), np.bool_)  # read only: every sample is tried
    for q in prange(points.shape[0] * n_m):
        p = q // n_m
        m = q - p * n_m
        if where[p, m]:
            sel = np.empty((3, 6))
            wit, bp, pieces, pick, cnt = pose_scratch(cos_t.shape[1])
            out[p, m] = _pose_clear(points[p, 0], points[p, 1], points[p, 2], us[m], cos_t, sin_t, arc, hb,
                                    rho_lo, rho_hi, lmin2, lmax2, jcs[m], dmin, sel, skip, 0,
                                    wit, bp, pieces, pick, cnt, True)


def interference_free(design: Design, joints: Joints, points: np.ndarray, rotations: np.ndarray, n_eta: int,
                      where: np.ndarray | None = None) -> np.ndarray:
    """Whether each (point, rotation) pose has a carriage configuration found by the witness search
    (module docstring) in which all legs clear each other: bool array (N, M). Poses where ``where``
    is False are skipped (False in the result)."""
    from .feasibility import ChainTables

    pts = np.ascontiguousarray(np.asarray(points, dtype=np.float64).reshape(-1, 3))
    rots = np.asarray(rotations, dtype=np.float64).reshape(-1, 3, 3)
    out = np.zeros((pts.shape[0], rots.shape[0]), np.bool_)
    if not out.size:
        return out
    mask = np.ones(out.shape, np.bool_) if where is None else np.ascontiguousarray(where, dtype=np.bool_)
    tab = ChainTables(design, n_eta)
    local = platform_points_local(design)
    us = np.ascontiguousarray(np.einsum("ijk,mlk->mijl", local, rots))
    jcs = np.ascontiguousarray(np.stack([cone_table(design, joints, r) for r in rots]))
    with KERNEL_LOCK:
        _clear_kernel(pts, us, jcs, tab.cos_t, tab.sin_t, tab.arc, tab.hb, tab.rho_lo, tab.rho_hi, tab.lmin2,
                      tab.lmax2, float(joints.min_distance), mask, out)
    return out


def clear_configuration(design: Design, joints: Joints, position, rotation: np.ndarray,
                        n_eta: int) -> tuple[np.ndarray, np.ndarray] | None:
    """The carriage configuration ``(d, eta_deg)`` (each shape (3,)) that the witness search of the
    module docstring finds for one platform pose, or ``None`` when it finds none (also when a chain
    fails the stroke or cone limits). With ``leg_diameter = 0`` every witness clears."""
    from .feasibility import ChainTables

    tab = ChainTables(design, n_eta)
    rot = np.asarray(rotation, dtype=np.float64).reshape(3, 3)
    u = np.ascontiguousarray(platform_points_local(design) @ rot.T)
    jc = cone_table(design, joints, rot)
    sel = np.zeros((3, 6))
    px, py, pz = (float(v) for v in np.asarray(position, dtype=float).reshape(3))
    with KERNEL_LOCK:
        ok = _pose_clear(px, py, pz, u, tab.cos_t, tab.sin_t, tab.arc, tab.hb, tab.rho_lo, tab.rho_hi, tab.lmin2,
                         tab.lmax2, jc, float(joints.min_distance), sel, np.zeros((1,) + tab.cos_t.shape, np.bool_),
                         0, *pose_scratch(tab.cos_t.shape[1]), True)
    if not ok:
        return None
    mid = 0.5 * (sel[:, 0:2] + sel[:, 3:5])  # carriage centre rho e on the base plane
    rho = np.hypot(mid[:, 0], mid[:, 1])
    from .geometry import GAMMA

    eta = np.degrees(np.angle(np.exp(1j * (np.arctan2(mid[:, 1], mid[:, 0]) - GAMMA))))
    return design.r - rho, eta
