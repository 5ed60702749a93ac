"""Leg interference on a voxel grid, decided block by block: the same voxels as the per-voxel
witness search of :mod:`kinematics.interference`, with its work spent near where legs come close.

Lemma (Lipschitz). For a fixed carriage pose every S joint is ``B = P + R u`` and every U joint
``D`` is fixed, so moving the platform centre by ``v`` moves the point ``D + s (B - D)`` of a leg by
``s v``; the distance of two legs (:func:`kinematics.interference.segment_distance`) changes by at
most ``|s - t| |v| <= |v|``. Moving a carriage by ``dr`` along its rail moves its U joints by ``dr``
and the points of its legs by ``(1 - s) dr``, so the distance changes by at most ``|dr|``.

Own legs (the two legs of one carriage, nearly parallel, so ``|s - t|`` stays small). Both moves
shift leg 1's vector ``X = B_1 - D_1`` by ``dX`` with ``|dX| <= |v| + |dr|`` and move the points
``(s, t)`` apart by ``(s - t) dX``. With ``(s0, t0)`` the closest points and ``d0`` the distance
before the move, ``a``, ``b`` the legs' vectors and ``g = a - b``:

* upper bound ``d0 + |s0 - t0| |dX|`` (the same two points);
* lower bound: ``|w(s, t)|^2 >= d0^2 - r + |xi_s a - xi_t b|^2`` (a convex quadratic on the unit
  square, ``xi = (s, t) - (s0, t0)``, ``r`` the first-order optimality residual of the computed
  ``(s0, t0)``) and ``|xi_s a - xi_t b| >= |sigma| alpha`` with ``sigma = xi_s - xi_t`` and ``alpha``
  the part of ``a`` normal to ``g``; so the distance is at least ``min over 0 <= sigma <= 2`` of
  ``sqrt(d0^2 - r + sigma^2 alpha^2) - (|s0 - t0| + sigma) |dX|`` (closed form, :func:`_own_bounds`).

Let a block be a box of voxel centres with centre ``Pc`` and half-diagonal ``delta``, ``e = delta +
eps`` (``eps`` the rounding margin of :func:`kinematics.blocks.rounding_margin`). For a chain, walk
the arc samples in the witness search's order (outward from the middle sample, turned for ``y < 0``:
:func:`kinematics.interference.scan_sample`; no block holds centres of both signs of ``y``, below) and
keep in ``K``:

* nothing for a sample that fails at ``Pc`` with the leg limits relaxed by ``e`` (cones by ``(1 + k)
  e``): it fails at every centre of the block (:mod:`kinematics.blocks`), so it is no witness there;
  nor for a sample whose two legs stay below ``d_min`` over its whole relaxed hull (below);
* for any other sample, the hull ``[r0, r1]`` of its relaxed feasible ``rho`` at ``Pc``: at every
  centre ``P`` of the block the sample's feasible ``rho`` (hence every probe of the witness search)
  lies in it;
* and stop at the first sample (of at most :data:`MAX_OWN` that pass the tightened test) where some
  probe clears at every centre. The feasible set at ``P`` lies between the tightened set at ``Pc``
  (``[t0, t1]`` its hull) and the relaxed one, so the first probe (the least feasible ``rho``: the
  pieces come in increasing ``rho``) lies in ``[r0, t0]``; when no leg's gap (the ``rho`` where it is
  shorter than ``l_min``) splits ``[r0, r1]`` at any ``P`` (:func:`_no_split`: its gap with the lower
  limit tightened misses ``[r0, r1]``, or its gap with the lower limit relaxed, which the gap at ``P``
  contains, reaches past an end of it) the set is one interval at every ``P`` and the next probes, its
  greatest and middle ``rho``, lie in ``[t1, r1]`` and ``[(r0 + t1) / 2, (t0 + r1) / 2]``. A probe
  range whose legs stay ``d_min`` apart under every move of at most ``e`` (own-leg lower bound,
  bisection of the range) stops the search there at every ``P``; the ranges tried before it whose
  legs do not always collide replace the sample's hull.

**Clear.** At every centre of the block each chain's first witness is then a carriage pose ``(k,
rho)`` with ``k`` in ``K`` and ``rho`` in its hull. When, for every two chains and every pair of their
legs, the legs are at least ``d_min + e`` apart at ``Pc`` for every such pose (first with every U
joint a chain can use in a disc around the discs' centres, then sample pair by sample pair with a
bisection of both hulls), the first witnesses clear each other at every centre: the per-voxel search
answers "clear" at each of them (it accepts the first witnesses).

**Interferes.** When for some chain, at every sample that passes the relaxed test at ``Pc``, the
own-leg upper bound stays below ``d_min`` over the whole hull (bisection), no probe of that chain
clears at any centre: the per-voxel search finds no witness and answers "interferes".

**Marks.** Both tests meet arc samples that are no witness at any centre of the block (the first
two cases of the walk above: they fail relaxed, or their own legs always collide). Each block marks
those it meets (the interferes test walks a chain only up to its first sample that may serve, so it
costs what it did before the marks), and its children inherit the marks: a child's centres are
centres of the parent. Both tests and the per-voxel search pass over marked samples, which changes
no answer (a marked sample yields no witness, so the witness search finds the same witnesses in the
same order) and saves most of the scan of a chain whose own legs collide.

A block holding voxels outside ``where`` is not tested for clear (the children decide, so no answer
changes): the certificate proves every chain feasible at every centre, which a block across the
boundary of the engine's occupancy (its ``where``) does not have (none of them passed, default design,
h = 1). Any other block is split in eight, except that a block of at most two voxels across decides
its voxels at once (they would be its children). A single voxel is decided by the per-voxel search
itself (:func:`kinematics.interference._pose_clear`, with the marks of its block), so the result is
voxel-identical to it. It runs without the search's first step, the whole-stroke screen of each
chain: a shortcut for poses a chain does not reach, which changes no answer (no sample of an excluded
chain serves, so it has no witness) and never fires on the engine's ``where``, which every chain
reaches; it cost about a tenth of the engine's interference time at h = 1. Blocks with no voxel to
test are skipped. Distances get one more margin of ``1e-7`` of the design's scale so the rounding of
the closed-form distance never matters.

The top blocks are laid so that none holds voxel centres of both signs of ``y`` (their y edges start
at the first centre with ``y >= 0``), so each block walks in the order of all its centres.

**Mirror.** With ``mirror`` (the engine's own mirror: a mirror-symmetric design at a mirror-symmetric
orientation, a grid and a ``where`` symmetric under ``y -> -y``), the witness search commutes with the
mirror (:mod:`kinematics.interference`, step 2), so only the rows ``j >= n_y // 2`` are decided (the
middle row of an odd ``n_y``, at ``y = 0``, maps onto itself) and the others are copied from their
images ``n_y - 1 - j`` (:func:`_mirror_rows`): half the work.

Cost: about the number of blocks near poses where legs come within ``d_min`` of each other, instead
of every voxel of the workspace.
"""

from __future__ import annotations

import math

import numba
import numpy as np
from numba import njit, prange

from .blocks import child_offsets, n_children, rounding_margin, write_child
from .design import Design
from .feasibility import ChainTables, _leg_frames, _leg_intervals, _leg_sets, chain_points, cones_set
from .geometry import platform_points_local
from .interference import _pose_clear, pose_scratch, scan_sample, segment_closest, segment_distance
from .joints import Joints, cone_table
from .parallel import KERNEL_LOCK
from .progress import CancelToken, check
from .slices import strided

__all__ = ["interference_free_grid", "TOP"]

#: Edge (in voxels) of the coarsest blocks.
TOP = 16
#: Distance evaluations one hull-pair bisection may spend before the block is split instead.
MAX_EVAL = 16
#: Samples per chain whose own legs are tried as the last witness before the block is split instead.
MAX_OWN = 16
#: Blocks one thread decides with one set of scratch.
CHUNK = 16

UNDECIDED, DONE = 0, 1


@njit(cache=True, inline="always")
def _u_joints(rho, c, s, hb, leg):
    """U joint of leg ``leg`` (0 or 1) of a carriage at ``rho`` on the rail of direction ``(c, s)``."""
    if leg == 0:
        return rho * c - hb * s, rho * s + hb * c
    return rho * c + hb * s, rho * s - hb * c


@njit(cache=True)
def _relaxed_hull(b1x, b1y, b1z, b2x, b2y, b2z, c, s, hb, rho_lo, rho_hi, lo2, hi2, jc, cone_e):
    """Hull ``(ok, r0, r1, g1a, g1b, g2a, g2b)`` of the feasible ``rho`` at one carriage angle with the
    leg limits ``[lo2, hi2]`` (squared) and the cones relaxed by ``cone_e``, and each leg's gap
    ``(g_a, g_b)`` of (F2) (:mod:`kinematics.feasibility`; ``(1, 0)`` when it has none)."""
    ok, n1, a0, a1, a2, a3, n2, c0, c1, c2, c3, r_lo, r_hi = _leg_sets(
        b1x, b1y, b1z, b2x, b2y, b2z, c, s, hb, rho_lo, rho_hi, lo2, hi2, jc, cone_e)
    return _hull(ok, n1, a0, a1, a2, a3, n2, c0, c1, c2, c3, r_lo, r_hi)


@njit(cache=True, forceinline=True)
def _relaxed_hull_plain(b1x, b1y, b1z, b2x, b2y, b2z, c, s, hb, rho_lo, rho_hi, lo2, hi2):
    """:func:`_relaxed_hull` of a chain without joint cones: numbers only, no array argument (numba
    counts an atomic reference on each, per call)."""
    p1, _, q1, p2, _, q2 = _leg_frames(b1x, b1y, b1z, b2x, b2y, b2z, c, s, hb)
    n1, a0, a1, a2, a3 = _leg_intervals(p1, q1, lo2, hi2)
    n2, c0, c1, c2, c3 = _leg_intervals(p2, q2, lo2, hi2)
    return _hull(n1 > 0 and n2 > 0, n1, a0, a1, a2, a3, n2, c0, c1, c2, c3, rho_lo, rho_hi)


@njit(cache=True, inline="always")
def _hull(ok, n1, a0, a1, a2, a3, n2, c0, c1, c2, c3, r_lo, r_hi):
    """The hull and gaps of :func:`_relaxed_hull` from both legs' interval sets and the rail."""
    g1a, g1b = (a1, a2) if n1 == 2 else (1.0, 0.0)
    g2a, g2b = (c1, c2) if n2 == 2 else (1.0, 0.0)
    if not ok:
        return False, 0.0, 0.0, g1a, g1b, g2a, g2b
    # the (at most 2 x 2) pairs of the legs' intervals
    h0, h1 = _meet(1e300, -1e300, a0, a1, c0, c1, r_lo, r_hi)
    if n2 == 2:
        h0, h1 = _meet(h0, h1, a0, a1, c2, c3, r_lo, r_hi)
    if n1 == 2:
        h0, h1 = _meet(h0, h1, a2, a3, c0, c1, r_lo, r_hi)
        if n2 == 2:
            h0, h1 = _meet(h0, h1, a2, a3, c2, c3, r_lo, r_hi)
    return h0 <= h1, h0, h1, g1a, g1b, g2a, g2b


@njit(cache=True, inline="always")
def _hull_at(cones, b1x, b1y, b1z, b2x, b2y, b2z, c, s, hb, rho_lo, rho_hi, lo2, hi2, jc, cone_e):
    """:func:`_relaxed_hull` where the chain has joint cones (``cones``), else
    :func:`_relaxed_hull_plain` (the same numbers: without cones ``_leg_sets`` leaves the rail as it is)."""
    if cones:
        return _relaxed_hull(b1x, b1y, b1z, b2x, b2y, b2z, c, s, hb, rho_lo, rho_hi, lo2, hi2, jc, cone_e)
    return _relaxed_hull_plain(b1x, b1y, b1z, b2x, b2y, b2z, c, s, hb, rho_lo, rho_hi, lo2, hi2)


@njit(cache=True, inline="always")
def _meet(h0, h1, lo_a, hi_a, lo_b, hi_b, r_lo, r_hi):
    """The hull ``(h0, h1)`` grown by the meet of ``[lo_a, hi_a]``, ``[lo_b, hi_b]`` and the rail."""
    lo = max(lo_a, lo_b, r_lo)
    hi = min(hi_a, hi_b, r_hi)
    if lo <= hi:
        return min(h0, lo), max(h1, hi)
    return h0, h1


@njit(cache=True, inline="always")
def _no_split(ga, gb, ha, hb, r0, r1):
    """Whether one leg's gap (its rho where the leg is shorter than ``l_min``) leaves one interval of
    the relaxed hull ``[r0, r1]`` at every centre of the block: the gap at a centre lies in the gap
    ``(ga, gb)`` at the block centre with the lower limit tightened, and holds the gap ``(ha, hb)`` at
    the block centre with it relaxed (an empty gap is ``(1, 0)``). So it does not split the hull when
    ``(ga, gb)`` misses ``(r0, r1)``, or when ``(ha, hb)`` reaches past one end of it (the gap at the
    centre is an interval that then covers that end)."""
    return ga > gb or gb <= r0 or ga >= r1 or (ha < hb and (ha < r0 or hb > r1))


@njit(cache=True, inline="always")
def _own_closest(rho, c, s, hb, b1x, b1y, b1z, b2x, b2y, b2z):
    """The two legs of one carriage (at ``rho`` on the rail ``(c, s)``, S joints ``B_1``, ``B_2``):
    their closest points' parameters ``(s0, t0)``, the legs' vectors ``a = B_1 - D_1`` and ``q = B_2 -
    D_2``, the vector ``w`` between the closest points and its length ``d0``, as numbers."""
    x1, y1 = _u_joints(rho, c, s, hb, 0)
    x2, y2 = _u_joints(rho, c, s, hb, 1)
    s0, t0 = segment_closest(x1, y1, 0.0, b1x, b1y, b1z, x2, y2, 0.0, b2x, b2y, b2z)
    ax, ay, az = b1x - x1, b1y - y1, b1z
    qx, qy, qz = b2x - x2, b2y - y2, b2z
    wx = x1 + ax * s0 - (x2 + qx * t0)
    wy = y1 + ay * s0 - (y2 + qy * t0)
    wz = az * s0 - qz * t0
    d0 = math.sqrt(wx * wx + wy * wy + wz * wz)
    return s0, t0, ax, ay, az, qx, qy, qz, wx, wy, wz, d0


@njit(cache=True, forceinline=True)
def _own_bounds(rho, c, s, hb, b1x, b1y, b1z, b2x, b2y, b2z, shift):
    """Lower and upper bounds ``(lo, hi, d0)`` of the distance of the two legs of one carriage (S
    joints ``B_1 = (b1x, b1y, b1z)`` and ``B_2``, the carriage at ``rho`` on the rail ``(c, s)``; ``d0`` the distance
    before the move) after the platform and the carriage move so that leg 1's vector ``X = B_1 -
    D_1`` moves by at most ``shift`` (module doc, own legs)."""
    s0, t0, ax, ay, az, qx, qy, qz, wx, wy, wz, d0 = _own_closest(rho, c, s, hb, b1x, b1y, b1z, b2x, b2y, b2z)
    lam = abs(s0 - t0)
    hi = d0 + lam * shift
    # f = |w|^2 grows from (s0, t0) by at least |xi_s a - xi_t b|^2 less the KKT residual of (s0, t0)
    gs = 2.0 * (wx * ax + wy * ay + wz * az)
    gt = -2.0 * (wx * qx + wy * qy + wz * qz)
    res = 0.0
    res += abs(gs) if 0.0 < s0 < 1.0 else (max(-gs, 0.0) if s0 <= 0.0 else max(gs, 0.0))
    res += abs(gt) if 0.0 < t0 < 1.0 else (max(-gt, 0.0) if t0 <= 0.0 else max(gt, 0.0))
    f0 = max(d0 * d0 - res, 0.0)
    gx, gy, gz = ax - qx, ay - qy, az - qz
    aa = ax * ax + ay * ay + az * az
    gg = gx * gx + gy * gy + gz * gz
    ag = ax * gx + ay * gy + az * gz
    alpha2 = max(aa - ag * ag / gg, 0.0) if gg > 0.0 else aa
    alpha = math.sqrt(alpha2)
    # min over sigma in [0, 2] of sqrt(f0 + sigma^2 alpha^2) - sigma shift (convex in sigma)
    if alpha > shift:
        sig = shift * math.sqrt(f0) / (alpha * math.sqrt(alpha2 - shift * shift))
        sig = min(sig, 2.0)
    else:
        sig = 2.0
    lo = math.sqrt(f0 + sig * sig * alpha2) - sig * shift - lam * shift
    return lo, hi, d0


@njit(cache=True, forceinline=True)
def _own_upper(rho, c, s, hb, b1x, b1y, b1z, b2x, b2y, b2z, shift):
    """The upper bound and the distance before the move, ``(hi, d0)``, of :func:`_own_bounds` (the same
    numbers), without the lower bound: the test that a sample's own legs always collide needs only
    these, and it runs at most samples the blocks visit."""
    s0, t0, _, _, _, _, _, _, _, _, _, d0 = _own_closest(rho, c, s, hb, b1x, b1y, b1z, b2x, b2y, b2z)
    return d0 + abs(s0 - t0) * shift, d0


@njit(cache=True, forceinline=True)
def _own_legs(b1x, b1y, b1z, b2x, b2y, b2z, c, s, hb, r0, r1, e, thr, clear):
    """Whether the two legs of one carriage (S joints ``B_1``, ``B_2``) are at least ``thr`` apart
    (``clear``) or below ``thr`` (not ``clear``) for every ``rho`` in ``[r0, r1]`` and every platform
    move of at most ``e`` (bisection of the rail range with :func:`_own_bounds`'s lower bound, or
    :func:`_own_upper`'s upper one, at most :data:`MAX_EVAL` bounds). The bisection walks the dyadic
    pieces ``[r0 + j w, r0 + (j + 1) w]``, ``w = (r1 - r0) / 2^d``, depth first (the right half
    first) by their indices ``(d, j)`` alone: no stack, so no array argument (numba counts an atomic
    reference on each, in a function that loops). It gives up (False) at a piece whose bound misses
    ``thr`` by more than bisecting the piece could make up."""
    d = 0
    j = 0
    evals = 0
    while True:
        w = (r1 - r0) / (1 << d)
        a, b = r0 + j * w, r0 + (j + 1) * w
        rho, shift = 0.5 * (a + b), e + 0.5 * (b - a)
        if clear:
            lo, _, d0 = _own_bounds(rho, c, s, hb, b1x, b1y, b1z, b2x, b2y, b2z, shift)
            decided = lo >= thr
        else:
            hi, d0 = _own_upper(rho, c, s, hb, b1x, b1y, b1z, b2x, b2y, b2z, shift)
            decided = hi <= thr
        evals += 1
        if decided:  # this piece is decided: on to the next
            while d > 0 and j % 2 == 0:  # a left half: its parent is done too
                j //= 2
                d -= 1
            if d == 0:
                return True
            j -= 1  # a right half: its left sibling is next
            continue
        # not decided. The piece cannot be when a point of it fails, nor (a heuristic, which changes no
        # answer: False only splits the block) when its bound misses by more than bisecting it to the
        # end could gain: the distance at the middles moves by at most |s - t| <= 1 times the shift
        # in rho, sigma <= 2 and lambda <= 1 times the shift, w / 2 summed over the levels
        if clear:
            if d0 < thr or lo + 2.0 * (b - a) < thr:
                return False
        elif d0 > thr or hi - (b - a) > thr:
            return False
        if evals > MAX_EVAL:
            return False
        d += 1
        j = 2 * j + 1  # the right half first


@njit(cache=True, forceinline=True)
def _pair_clear(ax, ay, az, ca, sa, hba, la, a0, a1, bx, by, bz, cb, sb, hbb, lb, b0, b1, need, stack):
    """Whether leg ``la`` of a carriage on rail ``(ca, sa)`` (``rho`` in ``[a0, a1]``, S joint ``a*``)
    and leg ``lb`` of another on rail ``(cb, sb)`` (``rho`` in ``[b0, b1]``) are at least ``need`` apart
    for every pair of ``rho`` (bisection of the wider range; the lemma bounds the change by the sum
    of the half-widths; ``stack``: scratch of shape (64, 4))."""
    stack[0, 0], stack[0, 1], stack[0, 2], stack[0, 3] = a0, a1, b0, b1
    top = 1
    evals = 0
    while top > 0:
        top -= 1
        p, q, r, t = stack[top, 0], stack[top, 1], stack[top, 2], stack[top, 3]
        ma, mb = 0.5 * (p + q), 0.5 * (r + t)
        x1, y1 = _u_joints(ma, ca, sa, hba, la)
        x2, y2 = _u_joints(mb, cb, sb, hbb, lb)
        d = segment_distance(x1, y1, 0.0, ax, ay, az, x2, y2, 0.0, bx, by, bz)
        evals += 1
        if d < need or evals > MAX_EVAL or top + 2 > 64:
            return False
        if d - 0.5 * (q - p) - 0.5 * (t - r) >= need:
            continue
        if q - p >= t - r:
            stack[top, 0], stack[top, 1], stack[top, 2], stack[top, 3] = p, ma, r, t
            stack[top + 1, 0], stack[top + 1, 1], stack[top + 1, 2], stack[top + 1, 3] = ma, q, r, t
        else:
            stack[top, 0], stack[top, 1], stack[top, 2], stack[top, 3] = p, q, r, mb
            stack[top + 1, 0], stack[top + 1, 1], stack[top + 1, 2], stack[top + 1, 3] = p, q, mb, t
        top += 2
    return True


@njit(cache=True, forceinline=True)
def _block_clear(px, py, pz, e, u, cos_t, sin_t, hb, rho_lo, rho_hi, lmin, lmax, jc, dmin, margin, skip, sb, stack,
                 ks, hull, bx, by, bz, nk, cen, rad, flip):
    """The module doc's certificate at the block centre ``P`` with ``e = delta + eps``: True when
    every centre of the block is clear (``skip[sb]`` (3, n): samples known to be no witness anywhere
    in the block, passed over; ``stack``, ``ks`` (3, n), ``hull`` (3, n, 2), ``bx/by/bz`` (3, 2),
    ``nk`` (3,), ``cen`` (3, 2, 2), ``rad`` (3, 2): scratch, from :func:`_block_scratch`). ``flip``:
    the block's centres have ``y < 0`` (the witness search's order for them)."""
    need = dmin + e + margin
    n = cos_t.shape[1]
    lo_r = max(lmin - e, 0.0)
    hi_r = lmax + e
    lo_r2, hi_r2 = lo_r * lo_r, hi_r * hi_r
    lo_t, hi_t = lmin + e, lmax - e
    if lo_t > hi_t:
        return False
    lo_t2, hi_t2 = lo_t * lo_t, hi_t * hi_t
    nk[:] = 0
    for i in range(3):
        b1x, b1y, b1z, b2x, b2y, b2z = chain_points(px, py, pz, u, i)
        bx[i, 0], by[i, 0], bz[i, 0] = b1x, b1y, b1z
        bx[i, 1], by[i, 1], bz[i, 1] = b2x, b2y, b2z
        jci = jc[i]  # one view per chain, not one per sample (each costs two atomic reference counts)
        cones = cones_set(jci)
        stopped = False
        tries = 0
        for step in range(n):  # the witness search's order (interference._witnesses)
            k = scan_sample(step, n, flip)
            if k < 0 or skip[sb, i, k]:
                continue
            c, s = cos_t[i, k], sin_t[i, k]
            ok, r0, r1, h1a, h1b, h2a, h2b = _hull_at(cones, b1x, b1y, b1z, b2x, b2y, b2z, c, s, hb, rho_lo, rho_hi,
                                                           lo_r2, hi_r2, jci, e)
            if not ok or _own_legs(b1x, b1y, b1z, b2x, b2y, b2z, c, s, hb, r0, r1, e, dmin - margin, False):
                skip[sb, i, k] = True  # it fails, or its own legs collide at every probe and centre: never a witness
                continue
            ks[i, nk[i]] = k
            hull[i, nk[i], 0], hull[i, nk[i], 1] = r0, r1
            nk[i] += 1
            okt, t0, t1, g1a, g1b, g2a, g2b = _hull_at(cones, b1x, b1y, b1z, b2x, b2y, b2z, c, s, hb, rho_lo, rho_hi,
                                                            lo_t2, hi_t2, jci, -e)
            # the feasible set is one interval at every centre when no leg's gap splits the relaxed hull
            one = _no_split(g1a, g1b, h1a, h1b, r0, r1) and _no_split(g2a, g2b, h2a, h2b, r0, r1)
            if okt:
                tries += 1
                if tries > MAX_OWN:
                    return False
                # the probes' ranges over the block (module doc): the least feasible rho in [r0, t0];
                # with one interval also the greatest in [t1, r1], then the middle
                w0, w1 = 1e300, -1e300
                for probe in range(3 if one else 1):
                    q0, q1 = (r0, t0) if probe == 0 else ((t1, r1) if probe == 1 else
                                                          (0.5 * (r0 + t1), 0.5 * (t0 + r1)))
                    if _own_legs(b1x, b1y, b1z, b2x, b2y, b2z, c, s, hb, q0, q1, e, dmin + margin, True):
                        hull[i, nk[i] - 1, 0], hull[i, nk[i] - 1, 1] = min(w0, q0), max(w1, q1)
                        stopped = True
                        break
                    if not _own_legs(b1x, b1y, b1z, b2x, b2y, b2z, c, s, hb, q0, q1, e, dmin - margin, False):
                        w0, w1 = min(w0, q0), max(w1, q1)
                if stopped:
                    break
                if one:  # the witness, if here, is a probe whose range does not always collide
                    if w0 > w1:
                        nk[i] -= 1
                    else:
                        hull[i, nk[i] - 1, 0], hull[i, nk[i] - 1, 1] = w0, w1
        if not stopped:
            return False
    # every U joint a chain's first witness can use lies within ``rad`` of ``cen`` (per chain and leg)
    rad[:] = 0.0
    for i in range(3):
        for la in range(2):
            x_lo, x_hi, y_lo, y_hi = 1e300, -1e300, 1e300, -1e300
            for a in range(nk[i]):
                for r in range(2):
                    x, y = _u_joints(hull[i, a, r], cos_t[i, ks[i, a]], sin_t[i, ks[i, a]], hb, la)
                    x_lo, x_hi, y_lo, y_hi = min(x_lo, x), max(x_hi, x), min(y_lo, y), max(y_hi, y)
            cen[i, la, 0], cen[i, la, 1] = 0.5 * (x_lo + x_hi), 0.5 * (y_lo + y_hi)
            r2 = 0.0  # the largest squared distance, one square root after (libm's hypot was 3 % of the time)
            for a in range(nk[i]):
                for r in range(2):
                    x, y = _u_joints(hull[i, a, r], cos_t[i, ks[i, a]], sin_t[i, ks[i, a]], hb, la)
                    dx, dy = x - cen[i, la, 0], y - cen[i, la, 1]
                    r2 = max(r2, dx * dx + dy * dy)
            rad[i, la] = math.sqrt(r2)
    for i in range(3):
        for j in range(i + 1, 3):
            far = True
            for la in range(2):
                for lb in range(2):
                    dd = segment_distance(cen[i, la, 0], cen[i, la, 1], 0.0, bx[i, la], by[i, la], bz[i, la],
                                          cen[j, lb, 0], cen[j, lb, 1], 0.0, bx[j, lb], by[j, lb], bz[j, lb])
                    if dd - rad[i, la] - rad[j, lb] < need:
                        far = False
            if far:
                continue
            if nk[i] * nk[j] > 4:
                return False
            for a in range(nk[i]):
                ka = ks[i, a]
                for b in range(nk[j]):
                    kb = ks[j, b]
                    for la in range(2):
                        for lb in range(2):
                            if not _pair_clear(bx[i, la], by[i, la], bz[i, la], cos_t[i, ka], sin_t[i, ka], hb, la,
                                               hull[i, a, 0], hull[i, a, 1],
                                               bx[j, lb], by[j, lb], bz[j, lb], cos_t[j, kb], sin_t[j, kb], hb, lb,
                                               hull[j, b, 0], hull[j, b, 1], need, stack):
                                return False
    return True


@njit(cache=True, forceinline=True)
def _exclude(px, py, pz, e, u, cos_t, sin_t, hb, rho_lo, rho_hi, lmin, lmax, jc, dmin, margin, skip, sb, bx, by,
             bz):
    """Mark in ``skip[sb]`` (3, n) every arc sample that is no witness of its chain at any centre of the
    block (``e = delta + eps``; samples already marked, by the parent block, are not tested again):
    it fails at ``P`` with the limits relaxed by ``e``, or its two legs stay below ``d_min - margin``
    over the relaxed hull after any move of at most ``e`` (every probe of the witness search
    collides). Returns True when some chain has every sample marked: it has no witness at any
    centre, and the per-voxel search answers "interferes" there (module doc)."""
    n = cos_t.shape[1]
    lo_r = max(lmin - e, 0.0)
    hi_r = lmax + e
    lo_r2, hi_r2 = lo_r * lo_r, hi_r * hi_r
    for i in range(3):
        b1x, b1y, b1z, b2x, b2y, b2z = chain_points(px, py, pz, u, i)
        bx[i, 0], by[i, 0], bz[i, 0] = b1x, b1y, b1z
        bx[i, 1], by[i, 1], bz[i, 1] = b2x, b2y, b2z
        jci = jc[i]
        cones = cones_set(jci)
        alive = False
        for k in range(n):
            if skip[sb, i, k]:
                continue
            c, s = cos_t[i, k], sin_t[i, k]
            ok, r0, r1, _, _, _, _ = _hull_at(cones, b1x, b1y, b1z, b2x, b2y, b2z, c, s, hb, rho_lo, rho_hi, lo_r2,
                                              hi_r2, jci, e)
            if not ok or _own_legs(b1x, b1y, b1z, b2x, b2y, b2z, c, s, hb, r0, r1, e, dmin - margin, False):
                skip[sb, i, k] = True
            else:
                alive = True
                break  # a chain with a possible witness: the rest of its samples stay to be tested
        if not alive:
            return True
    return False


@njit(cache=True)
def _block_scratch(n):
    """The scratch of :func:`_block_clear` and :func:`_exclude` for ``n`` arc samples: ``(stack, ks,
    hull, bx, by, bz, nk, cen, rad)``."""
    return (np.empty((64, 4)), np.empty((3, n), np.int64), np.empty((3, n, 2)), np.empty((3, 2)),
            np.empty((3, 2)), np.empty((3, 2)), np.empty(3, np.int64), np.empty((3, 2, 2)), np.empty((3, 2)))


@njit(cache=True, inline="always")
def _box_count(where, x0, y0, z0, nx, ny, nz):
    """The voxels of ``where`` in the box of ``nx x ny x nz`` voxels from ``(x0, y0, z0)``, counted along
    z runs (a loop the compiler puts in vector lanes). A summed-volume table answered this at four
    bytes a voxel of the grid (654 MB at h = 0.5) and took longer to build (15 ms at h = 1) than the
    counts of every level together."""
    c = 0
    for x in range(x0, x0 + nx):
        for y in range(y0, y0 + ny):
            for z in range(z0, z0 + nz):
                c += where[x, y, z]
    return c


@njit(parallel=True, cache=True, nogil=True)
def _blocks_kernel(b0, bn, pskip, par, skip, where, xs, ys, zs, h, eps, margin, u, cos_t, sin_t, arc, hb, rho_lo,
                   rho_hi, lmin2, lmax2, jc, dmin, state, out, threads):
    """Decide each block: DONE (its voxels of ``where`` written to ``out``) or UNDECIDED, with the
    samples that are no witness anywhere in it marked in ``skip[b]`` (inherited by its children):
    block ``b`` starts from a copy of its parent's marks ``pskip[par[b]]``, to which its tests add. A
    block of at most two voxels across that its tests leave undecided (a single voxel is not tested)
    decides its voxels at once, with the per-voxel search and its own marks (its children would be
    those voxels): it is always DONE, so it keeps its marks in the thread's scratch, and the rows of
    such blocks are never written. Parallel over runs of :data:`CHUNK` blocks, each with one set of
    scratch (an allocation per block or voxel cost a call to the allocator and atomic reference
    counts each); every table is read in place, by index. The runs are visited in the strided order
    of :mod:`kinematics.slices` for the launch's ``threads``: the undecided blocks gather along the
    workspace's boundary, and numba gives each thread a contiguous slice of the launch."""
    lmin, lmax = math.sqrt(lmin2), math.sqrt(lmax2)
    nb = b0.shape[0]
    n = cos_t.shape[1]
    runs = (nb + CHUNK - 1) // CHUNK
    per = (runs + threads - 1) // threads
    for pos in prange(threads * per):
        c = strided(pos, per, threads)
        if c >= runs:
            continue
        sel = np.empty((3, 6))
        wit, bp, pieces, pick, cnt = pose_scratch(n)
        stack, ks, hull, bx, by, bz, nk, cen, rad = _block_scratch(n)
        own = np.empty((1, 3, n), np.bool_)  # the marks of a block of at most two voxels across
        for b in range(c * CHUNK, min(nb, c * CHUNK + CHUNK)):
            nin = _box_count(where, b0[b, 0], b0[b, 1], b0[b, 2], bn[b, 0], bn[b, 1], bn[b, 2])
            if nin == 0:  # no voxel to test
                state[b] = DONE
                continue
            nx, ny, nz = bn[b, 0], bn[b, 1], bn[b, 2]
            p = par[b]
            last = nx <= 2 and ny <= 2 and nz <= 2  # its children would be single voxels
            mk, row = (own, 0) if last else (skip, b)
            for i in range(3):
                for k in range(n):
                    mk[row, i, k] = pskip[p, i, k]
            px = 0.5 * (xs[b0[b, 0]] + xs[b0[b, 0] + nx - 1])
            py = 0.5 * (ys[b0[b, 1]] + ys[b0[b, 1] + ny - 1])
            pz = 0.5 * (zs[b0[b, 2]] + zs[b0[b, 2] + nz - 1])
            e = 0.5 * h * math.sqrt((nx - 1) ** 2 + (ny - 1) ** 2 + (nz - 1) ** 2) + eps
            # a block with voxels outside ``where`` is not tested for clear: in the engine's use (``where``
            # its occupancy) the certificate, which proves every chain feasible at every centre, never
            # holds there (the children decide; this saves time and changes no answer)
            tested = nx * ny * nz > 1  # a single voxel goes to the per-voxel search at once
            if tested and nin == nx * ny * nz and _block_clear(px, py, pz, e, u, cos_t, sin_t, hb, rho_lo, rho_hi,
                                                               lmin, lmax, jc, dmin, margin, mk, row, stack, ks, hull,
                                                               bx, by, bz, nk, cen, rad, py < 0.0):
                for x in range(b0[b, 0], b0[b, 0] + nx):
                    for y in range(b0[b, 1], b0[b, 1] + ny):
                        for z in range(b0[b, 2], b0[b, 2] + nz):
                            out[x, y, z] = where[x, y, z]
                state[b] = DONE
            elif tested and _exclude(px, py, pz, e, u, cos_t, sin_t, hb, rho_lo, rho_hi, lmin, lmax, jc, dmin, margin,
                                     mk, row, bx, by, bz):
                state[b] = DONE  # every voxel interferes: out stays False
            elif last:
                for ix in range(b0[b, 0], b0[b, 0] + nx):
                    for iy in range(b0[b, 1], b0[b, 1] + ny):
                        for iz in range(b0[b, 2], b0[b, 2] + nz):
                            if where[ix, iy, iz]:
                                out[ix, iy, iz] = _pose_clear(xs[ix], ys[iy], zs[iz], u, cos_t, sin_t, arc, hb, rho_lo,
                                                              rho_hi, lmin2, lmax2, jc, dmin, sel, own, 0, wit, bp,
                                                              pieces, pick, cnt, False)  # no screen (module doc)
                state[b] = DONE
            else:
                state[b] = UNDECIDED


def interference_free_grid(design: Design, joints: Joints, axes: tuple[np.ndarray, np.ndarray, np.ndarray],
                           h: float, rotation: np.ndarray, n_eta: int, where: np.ndarray,
                           cancel: CancelToken = None, mirror: bool = False) -> np.ndarray:
    """:func:`kinematics.interference.interference_free` at the voxel centres of a grid (``axes``, edge
    ``h``) at one ``rotation``, for the voxels where ``where`` is True (the others are False), decided
    block by block (module docstring): bool array of ``where``'s shape, the per-voxel answer at each
    voxel. ``mirror``: the caller states that the design, the ``rotation``, the y centres and
    ``where`` are symmetric under ``y -> -y`` (the engine's mirror, :meth:`WorkspaceSettings.mirror_symmetric`);
    the rows ``j < n_y // 2`` are then copied from their mirror images (module doc, Mirror)."""
    xs, ys, zs = (np.ascontiguousarray(a, dtype=np.float64) for a in axes)
    mask = np.ascontiguousarray(where, dtype=np.bool_)
    out = np.zeros(mask.shape, np.bool_)
    if not mask.any():
        return out
    tab = ChainTables(design, n_eta)
    rot = np.asarray(rotation, dtype=np.float64).reshape(1, 3, 3)
    u = np.ascontiguousarray(np.einsum("ijk,mlk->mijl", platform_points_local(design), rot)[0])
    jc = np.ascontiguousarray(cone_table(design, joints, rot[0]))
    lmax = math.sqrt(tab.lmax2)
    eps = rounding_margin(lmax, (xs, ys, zs))
    margin = 100.0 * eps  # 1e-7 of the design's scale (module doc)
    b0, bn = _top_blocks(mask.shape, ys, mirror)
    n = tab.cos_t.shape[1]
    pskip = np.zeros((1, 3, n), np.bool_)  # the top blocks' parent: no sample marked
    par = np.zeros(b0.shape[0], np.int64)
    step = 8192  # blocks per launch: cancellation within a fraction of a second
    while b0.shape[0]:
        state = np.empty(b0.shape[0], np.int8)
        # samples no witness in the block; np.empty maps a page when it is first written, and the
        # rows of single voxels never are
        skip = np.empty((b0.shape[0], 3, n), np.bool_)
        for s in range(0, b0.shape[0], step):
            check(cancel)
            with KERNEL_LOCK:
                _blocks_kernel(b0[s:s + step], bn[s:s + step], pskip, par[s:s + step], skip[s:s + step], mask,
                               xs, ys, zs, float(h), eps, margin, u, tab.cos_t, tab.sin_t, tab.arc, tab.hb, tab.rho_lo,
                               tab.rho_hi, tab.lmin2, tab.lmax2, jc, float(joints.min_distance), state[s:s + step], out,
                               numba.get_num_threads())
        with KERNEL_LOCK:
            b0, bn, par = _split_undecided(b0, bn, state)
        pskip = skip
    if mirror:
        with KERNEL_LOCK:
            _mirror_rows(out, mask)
    return out


def _top_blocks(shape: tuple[int, int, int], ys: np.ndarray, mirror: bool) -> tuple[np.ndarray, np.ndarray]:
    """The top blocks ``(b0, bn)`` (first voxel and size, (m, 3) int64): :data:`TOP` voxels across, their
    y edges starting at the first centre with ``y >= 0`` (so no block holds centres of both signs of
    ``y``: module doc), or with ``mirror`` only the rows from ``n_y // 2`` up (the middle row of an odd
    ``n_y`` a layer of its own when its centre lies below 0 by rounding)."""
    def edges(n: int, at: int, below: bool) -> np.ndarray:
        e = set(range(at, n, TOP)) | {n}
        if below:
            e |= set(range(at, 0, -TOP)) | {0}
        return np.array(sorted(e), np.int64)

    ny = shape[1]
    j0 = int(np.searchsorted(ys, 0.0, side="left"))  # the first centre with y >= 0
    if mirror:
        ey = np.union1d(edges(ny, max(j0, ny // 2), False), [ny // 2])
    else:
        ey = edges(ny, j0, True)
    axes = [edges(shape[0], 0, False), ey, edges(shape[2], 0, False)]
    gx, gy, gz = np.meshgrid(*(a[:-1] for a in axes), indexing="ij")
    sx, sy, sz = np.meshgrid(*(np.diff(a) for a in axes), indexing="ij")
    b0 = np.stack([gx.ravel(), gy.ravel(), gz.ravel()], axis=1).astype(np.int64)
    bn = np.stack([sx.ravel(), sy.ravel(), sz.ravel()], axis=1).astype(np.int64)
    return b0, bn


@njit(parallel=True, cache=True, nogil=True)
def _mirror_rows(out, where):
    """``out[:, j] = out[:, n_y - 1 - j] & where[:, j]`` for the rows ``j < n_y // 2`` (module doc,
    Mirror), parallel over x."""
    nx, ny, nz = out.shape
    for i in prange(nx):
        for j in range(ny // 2):
            for k in range(nz):
                out[i, j, k] = out[i, ny - 1 - j, k] and where[i, j, k]


@njit(parallel=True, cache=True, nogil=True)
def _split_undecided(b0, bn, state):
    """The UNDECIDED blocks of ``state`` split in eight as :func:`kinematics.blocks._split` does:
    ``(b0, bn, par)`` of the children, ``par`` each child's parent (its index in ``b0``), each block's
    consecutive (the order changes no answer: every block is decided on its own). Parallel over the
    blocks, with :func:`kinematics.blocks._advance`'s child counts, offsets and boxes."""
    nb = b0.shape[0]
    counts = np.zeros(nb, np.int64)
    for b in prange(nb):
        if state[b] == UNDECIDED:
            counts[b] = n_children(bn, b)
    offs = child_offsets(counts)
    n_kids = offs[nb]
    k0 = np.empty((n_kids, 3), np.int64)
    kn = np.empty((n_kids, 3), np.int64)
    par = np.empty(n_kids, np.int64)
    for b in prange(nb):
        if counts[b] == 0:
            continue
        m = offs[b]
        for d in range(8):
            if write_child(b0, bn, b, d, k0, kn, m):
                par[m] = b
                m += 1
    return k0, kn, par
