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
interference) join as more interval sets intersected in :func:`_feasible_at`.

The arc coordinate is sampled at ``n_eta`` equally spaced values that include both ends of the
stroke. The test can only miss carriage angles between samples: a pose is reported unreachable
only if every sample fails, so the error is one-sided (the computed set is an inner
approximation) and confined to poses whose feasible ``eta`` set is narrower than the spacing.
A whole-stroke bound (:func:`_chain_excluded`) rejects most unreachable poses before sampling; it
is conservative (it never rejects a reachable pose).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from .design import Design
from .geometry import GAMMA, LEG_SIGN

# Results of :func:`chain_search` for "no sample works".
NOT_FOUND = -1


@njit(cache=True, inline="always")
def chain_points(px, py, pz, u, i):
    """The two S joints ``B_1, B_2`` of chain ``i`` for the platform centre ``P``: ``P + (R u)_ij``
    (``u`` holds the rotated platform points, shape (3, 2, 3))."""
    return (px + u[i, 0, 0], py + u[i, 0, 1], pz + u[i, 0, 2],
            px + u[i, 1, 0], py + u[i, 1, 1], pz + u[i, 1, 2])


@njit(cache=True, inline="always")
def _leg_intervals(p, q, lmin2, lmax2):
    """(F2): the <= 2 intervals of rho for one leg as (n, lo0, hi0, lo1, hi1)."""
    if q > lmax2:
        return 0, 0.0, 0.0, 0.0, 0.0
    ro = math.sqrt(lmax2 - q)
    if lmin2 > q:
        ri = math.sqrt(lmin2 - q)
        return 2, p - ro, p - ri, p + ri, p + ro
    return 1, p - ro, p + ro, 0.0, 0.0


@njit(cache=True, inline="always")
def _overlap(lo_a, hi_a, lo_b, hi_b, rho_lo, rho_hi):
    lo = max(lo_a, lo_b, rho_lo)
    hi = min(hi_a, hi_b, rho_hi)
    return lo <= hi


@njit(cache=True)
def _feasible_at(b1x, b1y, b1z, b2x, b2y, b2z, c, s, hb, rho_lo, rho_hi, lmin2, lmax2):
    """Exact test in rho at one carriage angle (cos c, sin s): both legs' (F2) sets meet the rail."""
    p1 = b1x * c + b1y * s
    m1 = -b1x * s + b1y * c - hb
    n1, a0, a1, a2, a3 = _leg_intervals(p1, b1z * b1z + m1 * m1, lmin2, lmax2)
    if n1 == 0:
        return False
    p2 = b2x * c + b2y * s
    m2 = -b2x * s + b2y * c + hb
    n2, c0, c1, c2, c3 = _leg_intervals(p2, b2z * b2z + m2 * m2, lmin2, lmax2)
    if n2 == 0:
        return False
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


@njit(cache=True, inline="always")
def _contains_angle(d0, d1, target):
    """Whether ``[d0, d1]`` (d1 - d0 < 2 pi) contains ``target + 2 k pi`` for some integer k."""
    k = math.ceil((d0 - target) / (2.0 * math.pi))
    return target + 2.0 * math.pi * k <= d1


@njit(cache=True)
def _leg_excluded(bx, by, bz, sigma_hb, v0, v1, rho_lo, rho_hi, lmin2, lmax2):
    """Conservative rho-set of one leg over the whole arc stroke ``varpi in [v0, v1]``.

    Returns (empty, lo, hi, gap_lo, gap_hi): the leg's feasible rho for ANY varpi in the stroke lie in
    ``[lo, hi]`` minus the open gap ``(gap_lo, gap_hi)``.
    """
    rb = math.sqrt(bx * bx + by * by)
    beta = math.atan2(by, bx)
    d0 = beta - v1
    d1 = beta - v0
    ca, cb = math.cos(d0), math.cos(d1)
    sa, sb = math.sin(d0), math.sin(d1)
    cmax = 1.0 if _contains_angle(d0, d1, 0.0) else max(ca, cb)
    cmin = -1.0 if _contains_angle(d0, d1, math.pi) else min(ca, cb)
    smax = 1.0 if _contains_angle(d0, d1, 0.5 * math.pi) else max(sa, sb)
    smin = -1.0 if _contains_angle(d0, d1, -0.5 * math.pi) else min(sa, sb)
    p_lo, p_hi = rb * cmin, rb * cmax
    m_lo, m_hi = rb * smin - sigma_hb, rb * smax - sigma_hb
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
def _chain_excluded(b1x, b1y, b1z, b2x, b2y, b2z, hb, v0, v1, rho_lo, rho_hi, lmin2, lmax2):
    """Conservative whole-stroke rejection: True only if no carriage pose can serve the chain."""
    e1, lo1, hi1, g1lo, g1hi = _leg_excluded(b1x, b1y, b1z, hb, v0, v1, rho_lo, rho_hi, lmin2, lmax2)
    if e1:
        return True
    e2, lo2, hi2, g2lo, g2hi = _leg_excluded(b2x, b2y, b2z, -hb, v0, v1, rho_lo, rho_hi, lmin2, lmax2)
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
def chain_search(b1x, b1y, b1z, b2x, b2y, b2z, cos_t, sin_t, hb, rho_lo, rho_hi, lmin2, lmax2, start):
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
        if _feasible_at(b1x, b1y, b1z, b2x, b2y, b2z, cos_t[k], sin_t[k], hb, rho_lo, rho_hi, lmin2, lmax2):
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
        self.v0 = GAMMA + np.radians(lo)
        self.v1 = GAMMA + np.radians(hi)
        self.hb = 0.5 * design.b * LEG_SIGN[0]
        self.rho_lo, self.rho_hi = design.rho_limits
        self.lmin2 = design.l_min ** 2
        self.lmax2 = design.l_max ** 2


def default_n_eta(design: Design, eta_step_deg: float = 0.5) -> int:
    """Number of arc samples so that their spacing is at most ``eta_step_deg`` (both ends included)."""
    if design.eta_s <= 0:
        return 1
    return int(math.ceil(design.eta_s / eta_step_deg)) + 1
