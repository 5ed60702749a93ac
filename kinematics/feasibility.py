"""The per-chain reachability test: does SOME carriage pose ``(eta_i, d_i)`` inside the strokes put
both legs of chain ``i`` inside ``[l_min, l_max]``?  (Compiled with numba.)

Method (our documented definition, exact in ``d``, sampled in ``eta``):

For a fixed carriage angle ``varpi = gamma_i + eta`` let ``e = (cos varpi, sin varpi, 0)`` be the
radial rail direction and ``t = (-sin varpi, cos varpi, 0)``. The U joint of leg ``j`` is
``D_j = rho e + sigma_j (b/2) t`` with ``rho = r - d`` (eq. (11)), so it moves on a straight line,
and with ``p_j = B_j . e`` and ``q_j = B_jz^2 + (B_j . t - sigma_j b/2)^2``

    |B_j - D_j|^2 = (rho - p_j)^2 + q_j .                                              (F1)

``l_min^2 <= (F1) <= l_max^2`` therefore holds exactly for ``rho`` in at most two intervals

    |rho - p_j| <= sqrt(l_max^2 - q_j)   and   |rho - p_j| >= sqrt(l_min^2 - q_j)     (F2)

(empty when ``q_j > l_max^2``; the second condition is void when ``q_j < l_min^2``). A chain is
feasible at ``varpi`` iff the intersection of both legs' sets of (F2) with the rail
``[r - d_s, r]`` is non-empty. Further per-chain constraints (passive-joint cones, leg
interference) join as more interval sets intersected in :func:`_feasible_at`: the joint cones of
:mod:`kinematics.joints` are one more interval of ``rho`` per leg and joint (:func:`cone_interval`).

The arc coordinate is sampled at ``n_eta`` equally spaced values that include both ends of the
stroke. The test can only miss carriage angles between samples: a pose is reported unreachable
only if every sample fails, so the error is one-sided (the computed set is an inner
approximation) and confined to poses whose feasible ``eta`` set is narrower than the spacing.
A whole-stroke bound (:func:`_chain_excluded`) rejects most unreachable poses before sampling; it
is conservative (it never rejects a reachable pose). The workspace engines apply it with the leg
limits relaxed by a rounding margin (:func:`kinematics.blocks.rounding_margin`), so it never
contradicts a sample test in floating point: the decision is exactly "some arc sample passes".
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from .design import Design
from .geometry import GAMMA, LEG_SIGN

# Results of :func:`chain_search` for "no sample works".
NOT_FOUND = -1


@njit(cache=True, forceinline=True)
def chain_points(px, py, pz, u, i):
    """The two S joints ``B_1, B_2`` of chain ``i`` for the platform centre ``P``: ``P + (R u)_ij``
    (``u`` holds the rotated platform points, shape (3, 2, 3))."""
    return (px + u[i, 0, 0], py + u[i, 0, 1], pz + u[i, 0, 2],
            px + u[i, 1, 0], py + u[i, 1, 1], pz + u[i, 1, 2])


@njit(cache=True, forceinline=True)
def _leg_intervals(p, q, lmin2, lmax2):
    """(F2): the <= 2 intervals of rho for one leg as (n, lo0, hi0, lo1, hi1)."""
    if q > lmax2:
        return 0, 0.0, 0.0, 0.0, 0.0
    ro = math.sqrt(lmax2 - q)
    if lmin2 > q:
        ri = math.sqrt(lmin2 - q)
        return 2, p - ro, p - ri, p + ri, p + ro
    return 1, p - ro, p + ro, 0.0, 0.0


@njit(cache=True, forceinline=True)
def _overlap(lo_a, hi_a, lo_b, hi_b, rho_lo, rho_hi):
    lo = max(lo_a, lo_b, rho_lo)
    hi = min(hi_a, hi_b, rho_hi)
    return lo <= hi


@njit(cache=True, forceinline=True)
def sets_meet(n1, a0, a1, a2, a3, n2, c0, c1, c2, c3, rho_lo, rho_hi):
    """Whether some rho in ``[rho_lo, rho_hi]`` lies in both legs' sets: leg 1's ``n1`` intervals
    ``[a0, a1]`` (and ``[a2, a3]``) and leg 2's ``n2`` intervals ``[c0, c1]`` (and ``[c2, c3]``)."""
    if _overlap(a0, a1, c0, c1, rho_lo, rho_hi):
        return True
    if n2 == 2 and _overlap(a0, a1, c2, c3, rho_lo, rho_hi):
        return True
    if n1 == 2:
        if _overlap(a2, a3, c0, c1, rho_lo, rho_hi):
            return True
        if n2 == 2 and _overlap(a2, a3, c2, c3, rho_lo, rho_hi):
            return True
    return False


@njit(cache=True, forceinline=True)
def cone_interval(alpha, beta, k, p, q):
    """The set ``{rho : alpha + beta rho >= k sqrt((rho - p)^2 + q)}`` (joint cone (J1) of
    :mod:`kinematics.joints`, ``0 <= k < 1``, ``q >= 0``) as ``(lo, hi)``; empty when ``lo > hi``.

    The set is convex (``k L(rho) - alpha - beta rho`` is a convex function), hence one interval.
    With ``x = rho - p`` and ``f = alpha' + beta x`` (``alpha' = alpha + beta p``) it is
    ``{f >= 0} ∩ {g >= 0}``, ``g(x) = f^2 - k^2 (x^2 + q) = A x^2 + B x + C``: ``g < 0`` at the
    zero of ``f``, so of the two pieces of ``{g >= 0}`` only one meets ``{f >= 0}``.
    """
    big = 1e300
    a1 = alpha + beta * p
    # the half-line f >= 0
    if beta > 0.0:
        h_lo, h_hi = -a1 / beta, big
    elif beta < 0.0:
        h_lo, h_hi = -big, -a1 / beta
    elif a1 >= 0.0:
        h_lo, h_hi = -big, big
    else:
        return 1.0, 0.0
    if k <= 0.0:
        return h_lo + p, h_hi + p
    kk = k * k
    qa = beta * beta - kk
    qb = 2.0 * a1 * beta
    qc = a1 * a1 - kk * q
    if qa == 0.0:  # |beta| = k: g is affine
        if qb > 0.0:
            g_lo, g_hi = -qc / qb, big
        elif qb < 0.0:
            g_lo, g_hi = -big, -qc / qb
        elif qc >= 0.0:
            g_lo, g_hi = -big, big
        else:
            return 1.0, 0.0
        return max(g_lo, h_lo) + p, min(g_hi, h_hi) + p
    disc = qb * qb - 4.0 * qa * qc
    if disc < 0.0:
        if qa < 0.0:
            return 1.0, 0.0
        disc = 0.0
    sq = math.sqrt(disc)
    # numerically stable roots x1 <= x2
    t = -0.5 * (qb + sq) if qb >= 0.0 else -0.5 * (qb - sq)
    if t == 0.0:
        x1 = x2 = 0.0
    else:
        x1, x2 = t / qa, qc / t
    if x1 > x2:
        x1, x2 = x2, x1
    if qa < 0.0:  # {g >= 0} = [x1, x2]
        return max(x1, h_lo) + p, min(x2, h_hi) + p
    # qa > 0: {g >= 0} = (-inf, x1] U [x2, inf); f >= 0 keeps the ray on its side
    if beta > 0.0:
        return max(x2, h_lo) + p, h_hi
    return -big, min(x1, h_hi) + p


@njit(cache=True, forceinline=True)
def _leg_cones(jc, j, p, m, q, bx, by, bz, c, s, shb, e, lo, hi):
    """Intersect ``[lo, hi]`` with the U- and S-cone intervals of leg ``j`` ((J1), relaxed by
    ``(1 + k) e``: the cone function is (1 + k)-Lipschitz in the platform position)."""
    ku = jc[j, 6]
    if ku > -1.0:
        ae, at, az = jc[j, 0], jc[j, 1], jc[j, 2]
        a0, a1 = cone_interval(ae * p + at * m + az * bz + (1.0 + ku) * e, -ae, ku, p, q)
        lo, hi = max(lo, a0), min(hi, a1)
    ks = jc[j, 7]
    if ks > -1.0:
        nx, ny, nz = jc[j, 3], jc[j, 4], jc[j, 5]
        en = c * nx + s * ny
        tn = -s * nx + c * ny
        a0, a1 = cone_interval(bx * nx + by * ny + bz * nz - shb * tn + (1.0 + ks) * e, -en, ks, p, q)
        lo, hi = max(lo, a0), min(hi, a1)
    return lo, hi


@njit(cache=True, forceinline=True)
def _leg_frames(b1x, b1y, b1z, b2x, b2y, b2z, c, s, hb):
    """Each leg's S joint in its carriage's rail frame at one carriage angle: ``(p1, m1, q1, p2, m2,
    q2)``, ``p`` along the rail, ``m`` across it from the U joint's offset, ``q = z^2 + m^2`` (F2)."""
    p1 = b1x * c + b1y * s
    m1 = -b1x * s + b1y * c - hb
    q1 = b1z * b1z + m1 * m1
    p2 = b2x * c + b2y * s
    m2 = -b2x * s + b2y * c + hb
    q2 = b2z * b2z + m2 * m2
    return p1, m1, q1, p2, m2, q2


@njit(cache=True, forceinline=True)
def cones_set(jci):
    """Whether a chain's cone table ``jci`` (2, 8) (:func:`kinematics.joints.cone_table`) sets a joint
    cone (``k = -1`` marks none; every leg has the same two)."""
    return jci[0, 6] > -1.0 or jci[0, 7] > -1.0


@njit(cache=True, forceinline=True)
def _leg_sets(b1x, b1y, b1z, b2x, b2y, b2z, c, s, hb, rho_lo, rho_hi, lmin2, lmax2, jc, cone_e):
    """Both legs' (F2) interval sets at one carriage angle and the rail ``[rho_lo, rho_hi]`` cut by
    the joint cones: ``(ok, n1, a0, a1, a2, a3, n2, c0, c1, c2, c3, rho_lo, rho_hi)``; ``ok`` is
    False when a set is already empty."""
    p1, m1, q1, p2, m2, q2 = _leg_frames(b1x, b1y, b1z, b2x, b2y, b2z, c, s, hb)
    n1, a0, a1, a2, a3 = _leg_intervals(p1, q1, lmin2, lmax2)
    n2, c0, c1, c2, c3 = _leg_intervals(p2, q2, lmin2, lmax2)
    if n1 == 0 or n2 == 0:
        return False, n1, a0, a1, a2, a3, n2, c0, c1, c2, c3, rho_lo, rho_hi
    if cones_set(jc):
        rho_lo, rho_hi = _leg_cones(jc, 0, p1, m1, q1, b1x, b1y, b1z, c, s, hb, cone_e, rho_lo, rho_hi)
        rho_lo, rho_hi = _leg_cones(jc, 1, p2, m2, q2, b2x, b2y, b2z, c, s, -hb, cone_e, rho_lo, rho_hi)
    return rho_lo <= rho_hi, n1, a0, a1, a2, a3, n2, c0, c1, c2, c3, rho_lo, rho_hi


@njit(cache=True, forceinline=True)
def _mx(a, b):
    return a if a > b else b


@njit(cache=True, forceinline=True)
def _mn(a, b):
    return a if a < b else b


@njit(cache=True, forceinline=True)
def _passes(p1, q1, p2, q2, lo2, hi2, rho_lo, rho_hi):
    """The test of :func:`_feasible_sets` without cones, from both legs'
    ``p``, ``q`` (F1) and the squared leg limits ``lo2 <= hi2``, without branches (so that a loop
    over samples runs in SIMD lanes). The same answer as ``_leg_intervals`` + ``sets_meet``: a leg
    with ``q <= lo2`` has the one interval ``[p - ro, p + ro]``, here its two halves ``[p - ro, p]``
    and ``[p, p + ro]`` (``ri = 0``), which meet an interval iff it does (min and max are exact)."""
    ro1 = math.sqrt(_mx(hi2 - q1, 0.0))
    ro2 = math.sqrt(_mx(hi2 - q2, 0.0))
    return _parts_meet(p1, q1, ro1, p2, q2, ro2, lo2, rho_lo, rho_hi) & (q1 <= hi2) & (q2 <= hi2)


@njit(cache=True, forceinline=True)
def _parts_meet(p1, q1, ro1, p2, q2, ro2, lo2, rho_lo, rho_hi):
    """Whether a part of leg 1's set, a part of leg 2's and the rail meet (no branch): each leg's
    parts ``[p - ro, p - ri]`` and ``[p + ri, p + ro]`` with its outer radius ``ro`` given and
    ``ri = sqrt(max(lo2 - q, 0))`` (:func:`_passes`)."""
    ri1 = math.sqrt(_mx(lo2 - q1, 0.0))
    ri2 = math.sqrt(_mx(lo2 - q2, 0.0))
    a0, a1, a2, a3 = p1 - ro1, p1 - ri1, p1 + ri1, p1 + ro1
    c0, c1, c2, c3 = p2 - ro2, p2 - ri2, p2 + ri2, p2 + ro2
    return ((_mx(_mx(a0, c0), rho_lo) <= _mn(_mn(a1, c1), rho_hi))
            | (_mx(_mx(a0, c2), rho_lo) <= _mn(_mn(a1, c3), rho_hi))
            | (_mx(_mx(a2, c0), rho_lo) <= _mn(_mn(a3, c1), rho_hi))
            | (_mx(_mx(a2, c2), rho_lo) <= _mn(_mn(a3, c3), rho_hi)))


@njit(cache=True, forceinline=True)
def feasible_plain(b1x, b1y, b1z, b2x, b2y, b2z, c, s, hb, rho_lo, rho_hi, lo2, hi2):
    """:func:`_feasible_at` for a chain without joint cones (the same answer as its interval sets,
    :func:`_feasible_sets`: :func:`_passes`), for the squared leg limits ``lo2 <= hi2``, inlined. One
    test at a time, so it first answers the cheap cases with branches: a leg longer than the outer
    limit at every ``rho``, or the two legs' outer intervals (without their inner gaps) not meeting on
    the rail -- then no pair of their parts meets either, and :func:`_passes` is False too; else
    :func:`_passes`'s meet of the parts, with the outer radii already taken."""
    p1, _, q1, p2, _, q2 = _leg_frames(b1x, b1y, b1z, b2x, b2y, b2z, c, s, hb)
    if q1 > hi2 or q2 > hi2:
        return False
    ro1 = math.sqrt(hi2 - q1)
    ro2 = math.sqrt(hi2 - q2)
    if _mx(_mx(p1 - ro1, p2 - ro2), rho_lo) > _mn(_mn(p1 + ro1, p2 + ro2), rho_hi):
        return False
    return _parts_meet(p1, q1, ro1, p2, q2, ro2, lo2, rho_lo, rho_hi)  # its outer radii, not computed again


@njit(cache=True)
def _feasible_at(b1x, b1y, b1z, b2x, b2y, b2z, c, s, hb, rho_lo, rho_hi, lmin2, lmax2, jc, cone_e):
    """Exact test in rho at one carriage angle (cos c, sin s): both legs' (F2) sets meet the rail
    (and, when ``jc`` sets joint cones, both legs' cone intervals, relaxed by ``cone_e``). Without
    cones it runs :func:`feasible_plain` (the same answer, tested; no interval sets, early exits), else
    the interval sets themselves (:func:`_feasible_sets`). (The sets' test is inlined here, not
    called: measured, this function then stays a call in the engines' loops and is faster there.)"""
    if not cones_set(jc):
        return feasible_plain(b1x, b1y, b1z, b2x, b2y, b2z, c, s, hb, rho_lo, rho_hi, lmin2, lmax2)
    return _sets_test(b1x, b1y, b1z, b2x, b2y, b2z, c, s, hb, rho_lo, rho_hi, lmin2, lmax2, jc, cone_e)


@njit(cache=True, forceinline=True)
def _sets_test(b1x, b1y, b1z, b2x, b2y, b2z, c, s, hb, rho_lo, rho_hi, lmin2, lmax2, jc, cone_e):
    """Both legs' (F2) interval sets (cut by the joint cones where ``jc`` sets them) meet on the rail
    (:func:`_leg_sets`, :func:`sets_meet`): the definition of :func:`_feasible_at`."""
    ok, n1, a0, a1, a2, a3, n2, c0, c1, c2, c3, rho_lo, rho_hi = _leg_sets(
        b1x, b1y, b1z, b2x, b2y, b2z, c, s, hb, rho_lo, rho_hi, lmin2, lmax2, jc, cone_e)
    if not ok:
        return False
    return sets_meet(n1, a0, a1, a2, a3, n2, c0, c1, c2, c3, rho_lo, rho_hi)


@njit(cache=True)
def _feasible_sets(b1x, b1y, b1z, b2x, b2y, b2z, c, s, hb, rho_lo, rho_hi, lmin2, lmax2, jc, cone_e):
    """:func:`_feasible_at` by its definition, with or without cones (:func:`_sets_test`; the tests'
    reference for :func:`feasible_plain`)."""
    return _sets_test(b1x, b1y, b1z, b2x, b2y, b2z, c, s, hb, rho_lo, rho_hi, lmin2, lmax2, jc, cone_e)


@njit(cache=True, forceinline=True)
def piece_meet(ua, ub, a0, a1, a2, a3, c0, c1, c2, c3, rho_lo, rho_hi):
    """The meet ``(lo, hi)`` of leg 1's interval ``ua`` (``[a0, a1]``, or ``[a2, a3]`` when ``ua`` is
    1), leg 2's interval ``ub`` (``[c0, c1]`` or ``[c2, c3]``) and the rail ``[rho_lo, rho_hi]``;
    empty when ``lo > hi``. :func:`feasible_rho`'s pieces are these, ``ua`` outer, ``ub`` inner."""
    lo_a, hi_a = (a0, a1) if ua == 0 else (a2, a3)
    lo_b, hi_b = (c0, c1) if ub == 0 else (c2, c3)
    return max(lo_a, lo_b, rho_lo), min(hi_a, hi_b, rho_hi)


@njit(cache=True)
def feasible_rho(b1x, b1y, b1z, b2x, b2y, b2z, c, s, hb, rho_lo, rho_hi, lmin2, lmax2, jc, out):
    """The feasible set of ``rho`` at one carriage angle as at most 4 intervals written to ``out``
    (shape (4, 2)); returns their number (0: the angle does not serve the chain)."""
    ok, n1, a0, a1, a2, a3, n2, c0, c1, c2, c3, rho_lo, rho_hi = _leg_sets(
        b1x, b1y, b1z, b2x, b2y, b2z, c, s, hb, rho_lo, rho_hi, lmin2, lmax2, jc, 0.0)
    if not ok:
        return 0
    cnt = 0
    for u in range(n1):
        for v in range(n2):
            lo, hi = piece_meet(u, v, a0, a1, a2, a3, c0, c1, c2, c3, rho_lo, rho_hi)
            if lo <= hi:
                out[cnt, 0] = lo
                out[cnt, 1] = hi
                cnt += 1
    return cnt


@njit(cache=True, forceinline=True)
def _in_arc(wx, wy, c0, s0, c1, s1, cm, sm):
    """Whether the direction ``w`` lies in the stroke's arc ``[v0, v1]`` (at most a half-turn):
    ``(c0, s0, c1, s1, cm, sm) = (cos v0, sin v0, cos v1, sin v1, cos vm, sin vm)``, ``vm`` the arc's
    bisector."""
    return c0 * wy - s0 * wx >= 0.0 and wx * s1 - wy * c1 >= 0.0 and wx * cm + wy * sm >= 0.0


@njit(cache=True)
def _leg_excluded(bx, by, bz, sigma_hb, c0, s0, c1, s1, cm, sm, rho_lo, rho_hi, lmin2, lmax2):
    """Conservative rho-set of one leg over the whole arc stroke ``varpi in [v0, v1]``.

    ``p = B . e(varpi)`` and ``B . t(varpi)`` are ``|B_xy|`` times the cosine and sine of ``beta -
    varpi`` (``beta`` the polar angle of ``B``). Their extremes over the stroke are the values at
    the stroke ends (dot and cross products with the end directions) unless the polar direction,
    or its turn by 90, 180 or 270 degrees, lies inside the arc (then ``+-|B_xy|``): no ``atan2``.
    Returns (empty, lo, hi, gap_lo, gap_hi): the leg's feasible rho for ANY varpi in the stroke lie in
    ``[lo, hi]`` minus the open gap ``(gap_lo, gap_hi)``.
    """
    pa = bx * c1 + by * s1  # |B| cos(beta - v1)
    pb = bx * c0 + by * s0  # |B| cos(beta - v0)
    sa = by * c1 - bx * s1  # |B| sin(beta - v1)
    sb = by * c0 - bx * s0
    p_hi = max(pa, pb)
    p_lo = min(pa, pb)
    s_hi = max(sa, sb)
    s_lo = min(sa, sb)
    at_p = _in_arc(bx, by, c0, s0, c1, s1, cm, sm)
    at_m = _in_arc(-bx, -by, c0, s0, c1, s1, cm, sm)
    at_s = _in_arc(by, -bx, c0, s0, c1, s1, cm, sm)
    at_t = _in_arc(-by, bx, c0, s0, c1, s1, cm, sm)
    if at_p or at_m or at_s or at_t:
        rb = math.sqrt(bx * bx + by * by)
        if at_p:
            p_hi = rb
        if at_m:
            p_lo = -rb
        if at_s:
            s_hi = rb
        if at_t:
            s_lo = -rb
    m_lo, m_hi = s_lo - sigma_hb, s_hi - sigma_hb
    if m_lo <= 0.0 <= m_hi:
        m2min = 0.0
    else:
        m2min = min(m_lo * m_lo, m_hi * m_hi)
    m2max = max(m_lo * m_lo, m_hi * m_hi)
    qmin = bz * bz + m2min
    qmax = bz * bz + m2max
    if qmin > lmax2:
        return True, 0.0, 0.0, 0.0, 0.0
    ro = math.sqrt(lmax2 - qmin)
    lo, hi = max(p_lo - ro, rho_lo), min(p_hi + ro, rho_hi)
    if lo > hi:
        return True, 0.0, 0.0, 0.0, 0.0
    g_lo, g_hi = 1.0, 0.0
    if lmin2 > qmax:
        ri = math.sqrt(lmin2 - qmax)
        g_lo, g_hi = p_hi - ri, p_lo + ri
        if g_lo <= lo and hi <= g_hi:
            return True, 0.0, 0.0, 0.0, 0.0
    return False, lo, hi, g_lo, g_hi


@njit(cache=True)
def _chain_excluded(b1x, b1y, b1z, b2x, b2y, b2z, hb, arc, rho_lo, rho_hi, lmin2, lmax2):
    """Conservative whole-stroke rejection: True only if no carriage pose can serve the chain (the
    joint cones only shrink the feasible set, so the bound without them stays conservative).
    ``arc``: the stroke's 6 numbers (:func:`_in_arc`)."""
    return _excluded(b1x, b1y, b1z, b2x, b2y, b2z, hb, arc[0], arc[1], arc[2], arc[3], arc[4], arc[5], rho_lo,
                     rho_hi, lmin2, lmax2)


@njit(cache=True, forceinline=True)
def chain_excluded_at(b1x, b1y, b1z, b2x, b2y, b2z, hb, arcs, i, rho_lo, rho_hi, lmin2, lmax2):
    """:func:`_chain_excluded` over the stroke ``arcs[i]`` (``arcs`` (m, 6)), read in place: no view
    of the table is made (in a parallel loop each view costs two atomic reference counts on the
    table that every thread shares)."""
    return _excluded(b1x, b1y, b1z, b2x, b2y, b2z, hb, arcs[i, 0], arcs[i, 1], arcs[i, 2], arcs[i, 3], arcs[i, 4],
                     arcs[i, 5], rho_lo, rho_hi, lmin2, lmax2)


@njit(cache=True, forceinline=True)
def sub_arc_excluded_at(b1x, b1y, b1z, b2x, b2y, b2z, hb, seg_arc, i, g, rho_lo, rho_hi, lmin2, lmax2):
    """:func:`_chain_excluded` over the sub-arc ``seg_arc[i, g]`` (``seg_arc`` (3, m, 6)), read in
    place (:func:`chain_excluded_at`)."""
    return _excluded(b1x, b1y, b1z, b2x, b2y, b2z, hb, seg_arc[i, g, 0], seg_arc[i, g, 1], seg_arc[i, g, 2],
                     seg_arc[i, g, 3], seg_arc[i, g, 4], seg_arc[i, g, 5], rho_lo, rho_hi, lmin2, lmax2)


@njit(cache=True)
def _excluded(b1x, b1y, b1z, b2x, b2y, b2z, hb, c0, s0, c1, s1, cm, sm, rho_lo, rho_hi, lmin2, lmax2):
    """:func:`_chain_excluded` for the stroke given by its 6 numbers."""
    e1, lo1, hi1, g1lo, g1hi = _leg_excluded(b1x, b1y, b1z, hb, c0, s0, c1, s1, cm, sm, rho_lo, rho_hi, lmin2, lmax2)
    if e1:
        return True
    e2, lo2, hi2, g2lo, g2hi = _leg_excluded(b2x, b2y, b2z, -hb, c0, s0, c1, s1, cm, sm, rho_lo, rho_hi, lmin2,
                                             lmax2)
    if e2:
        return True
    lo, hi = max(lo1, lo2), min(hi1, hi2)
    if lo > hi:
        return True
    # the common interval is covered by one gap: nothing left
    if g1lo <= lo and hi <= g1hi:
        return True
    if g2lo <= lo and hi <= g2hi:
        return True
    return False


@njit(cache=True)
def chain_search(b1x, b1y, b1z, b2x, b2y, b2z, cos_t, sin_t, hb, rho_lo, rho_hi, lmin2, lmax2, jc, start):
    """Index of a feasible carriage-angle sample, searching outward from ``start``; -1 if none."""
    n = cos_t.shape[0]
    if start < 0 or start >= n:
        start = n // 2
    for step in range(2 * n):
        off = (step + 1) // 2
        k = start + off if step % 2 == 1 else start - off
        if k < 0 or k >= n:
            if off > n:
                break
            continue
        if _feasible_at(b1x, b1y, b1z, b2x, b2y, b2z, cos_t[k], sin_t[k], hb, rho_lo, rho_hi, lmin2, lmax2,
                        jc, 0.0):
            return k
    return NOT_FOUND


class ChainTables:
    """Precomputed per-design constants of the compiled test (sample tables of the arc stroke)."""

    def __init__(self, design: Design, n_eta: int) -> None:
        if n_eta < 1:
            raise ValueError("n_eta must be >= 1")
        lo, hi = design.eta_limits
        self.n_eta = n_eta if hi > lo else 1
        self.eta_deg = np.linspace(lo, hi, self.n_eta) if self.n_eta > 1 else np.array([lo])
        varpi = GAMMA[:, None] + np.radians(self.eta_deg)[None, :]
        self.cos_t = np.ascontiguousarray(np.cos(varpi))
        self.sin_t = np.ascontiguousarray(np.sin(varpi))
        v0, v1 = GAMMA + np.radians(lo), GAMMA + np.radians(hi)
        vm = 0.5 * (v0 + v1)
        #: per chain ``(cos v0, sin v0, cos v1, sin v1, cos vm, sin vm)``: the stroke's end and
        #: bisector directions (:func:`_leg_excluded`)
        self.arc = np.ascontiguousarray(np.stack([np.cos(v0), np.sin(v0), np.cos(v1), np.sin(v1),
                                                  np.cos(vm), np.sin(vm)], axis=1))
        self.hb = 0.5 * design.b * LEG_SIGN[0]
        self.rho_lo, self.rho_hi = design.rho_limits
        self.lmin2 = design.l_min ** 2
        self.lmax2 = design.l_max ** 2


def default_n_eta(design: Design, eta_step_deg: float = 0.5) -> int:
    """Number of arc samples so that their spacing is at most ``eta_step_deg`` (both ends included)."""
    if design.eta_s <= 0:
        return 1
    return int(math.ceil(design.eta_s / eta_step_deg)) + 1
