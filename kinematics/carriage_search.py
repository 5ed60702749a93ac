"""The resolver's full search of a chain's carriage pose, and the same search bounded by blocks.

Full search
-----------
Per chain ``i`` at a position, the redundancy resolution (:mod:`kinematics.redundancy`) takes the
carriage pose ``(eta, rho)`` (``rho = r - d``) of largest chain margin
``m_i(eta, rho) = min_j min(l_j - l_min, l_max - l_j)`` (:func:`_margin_cs`) by a
scan of a 73 x 61 grid on the strokes, then of two 21 x 21 zooms, each on the 4 x 4 cells around the
last grid's first maximiser (in scan order, ``eta`` major; :func:`best_carriage`, :func:`scan_argmax`).

**Lipschitz in the position**: at a fixed carriage pose a leg's length is 1-Lipschitz in the
platform position ``P`` (the U joint does not move, the S joint moves with ``P``), hence so is the
margin: ``m_i(Q; eta, rho) <= m_i(P; eta, rho) + |Q - P|`` (the bound of
:mod:`kinematics.dexterity_neighbour`'s restart scan).

Bounded
-------
Leg ``j``'s carriage joint is ``C_j = rho (cos phi, sin phi) + lat_j (-sin phi, cos phi)``,
``phi = gamma_i + eta``, ``lat_j = +-b/2``. Moving ``rho`` by ``d rho`` moves it by ``|d rho|``; moving
``eta`` by ``d eta`` at a fixed ``rho`` moves it along an arc of radius ``sqrt(rho^2 + (b/2)^2)``. A leg
length moves by at most its joint's move, and the margin (the least of terms ``l - l_min`` and
``l_max - l``) by at most the largest of its legs'. So within a block of grid points around a centre
``(eta_c, rho_c)``::

    m_i(eta, rho) <= m_i(eta_c, rho_c) + max |rho - rho_c| + max |eta - eta_c| sqrt(R^2 + (b/2)^2)

with ``R`` the block's largest ``|rho|``. :func:`bounded_argmax` splits each grid into blocks of
:data:`BLOCK` x :data:`BLOCK` points, computes the margin at every block's centre, then every point
of the blocks whose bound is not below the largest margin computed so far (less a slack of
``1e-7``), the block of the best centre first. A block left out holds only points below a margin
of the grid, so it holds no maximiser, and the first maximiser among the points computed is the
scan's: :func:`best_carriage` returns the full search's pose bit for bit
(:func:`resolve_kernel` with ``bounded=False`` is the reference the tests compare with). It
computes about a fifth of the full search's 5,300 margins per chain on the paper's design (about
22 us instead of 95 us per position and core; ``benchmarks/bench_workspace.py --throughput``).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit, prange

#: Slack of the pruning test (margins are lengths; it only adds grid points to compute).
_SLACK = 1e-7
#: The resolver's grids: coarse 73 x 61, zooms 21 x 21 (:func:`best_carriage`).
_NE, _NR, _NZ = 73, 61, 21

#: Grid points per side of a block of the bounded search (module docstring; 5 was the fastest of
#: 3-8 on the paper's design and the second design of the tests).
BLOCK = 5


@njit(cache=True, forceinline=True)
def chain_legs(bx0, by0, bz0, bx1, by1, bz1, c, s, rho, hb):
    """The ``y`` components ``dy`` of a chain's two leg vectors (S joint less U joint) and their
    lengths: ``(dy0, l0, dy1, l1)`` at one carriage pose (``c, s = cos, sin`` of the carriage angle
    ``varpi``; ``rho = r - d``; the U joints lie in the base plane)."""
    # leg 1: lateral +b/2, leg 2: -b/2 (LEG_SIGN)
    dx0 = bx0 - (c * rho - s * hb)
    dy0 = by0 - (s * rho + c * hb)
    dx1 = bx1 - (c * rho + s * hb)
    dy1 = by1 - (s * rho - c * hb)
    return (dy0, math.sqrt(dx0 * dx0 + dy0 * dy0 + bz0 * bz0), dy1,
            math.sqrt(dx1 * dx1 + dy1 * dy1 + bz1 * bz1))


@njit(cache=True, forceinline=True)
def _margin_cs(bx0, by0, bz0, bx1, by1, bz1, c, s, rho, hb, lmin, lmax):
    """The resolver's chain margin ``min_j min(l_j - l_min, l_max - l_j)`` at one carriage pose
    (``c, s = cos, sin`` of the carriage angle ``varpi``; ``rho = r - d``)."""
    _dy0, l0, _dy1, l1 = chain_legs(bx0, by0, bz0, bx1, by1, bz1, c, s, rho, hb)
    return min(min(l0 - lmin, lmax - l0), min(l1 - lmin, lmax - l1))


@njit(cache=True, forceinline=True)
def _lin(lo, hi, n, k):
    """``np.linspace(lo, hi, n)[k]``."""
    if n == 1:
        return lo
    if k == n - 1:
        return hi
    return lo + k * ((hi - lo) / (n - 1))


@njit(cache=True, forceinline=True)
def work_arrays():
    """The work arrays of :func:`bounded_argmax`: per grid row its cosine, sine and a flag,
    and the bound of every block of the coarse grid."""
    return np.empty((_NE, 3)), np.empty(((_NE + BLOCK - 1) // BLOCK) * ((_NR + BLOCK - 1) // BLOCK))


@njit(cache=True)
def scan_argmax(bx0, by0, bz0, bx1, by1, bz1, gamma, lo_e, hi_e, n_e, lo_r, hi_r, n_r, hb, lmin, lmax):
    """First maximiser ``(ke, kr)`` in scan order of the margin over the ``n_e x n_r`` grid on
    ``[lo_e, hi_e] x [lo_r, hi_r]``, every point computed (the full search's scan)."""
    best = -np.inf
    ke, kr = 0, 0
    for a in range(n_e):
        varpi = gamma + _lin(lo_e, hi_e, n_e, a)
        c, s = math.cos(varpi), math.sin(varpi)
        for b in range(n_r):
            m = _margin_cs(bx0, by0, bz0, bx1, by1, bz1, c, s, _lin(lo_r, hi_r, n_r, b), hb, lmin, lmax)
            if m > best:
                best, ke, kr = m, a, b
    return ke, kr


@njit(cache=True, forceinline=True)
def _row_trig(gamma, lo_e, hi_e, n_e, a, CS):
    """``CS[a] = (cos, sin, 1)`` of ``gamma + eta_a`` of grid row ``a``, computed once (``CS[a, 2]``)."""
    if CS[a, 2] == 0.0:
        varpi = gamma + _lin(lo_e, hi_e, n_e, a)
        CS[a, 0], CS[a, 1], CS[a, 2] = math.cos(varpi), math.sin(varpi), 1.0


@njit(cache=True)
def bounded_argmax(bx0, by0, bz0, bx1, by1, bz1, gamma, lo_e, hi_e, n_e, lo_r, hi_r, n_r, hb, lmin, lmax,
                   CS, UB):
    """First maximiser ``(ke, kr)`` in scan order of the margin over the ``n_e x n_r`` grid on
    ``[lo_e, hi_e] x [lo_r, hi_r]``, the full search's scan's, with the grid's points bounded by
    blocks (module docstring). Work arrays (:func:`work_arrays`): ``CS`` (at least n_e rows), ``UB``
    (at least one per block)."""
    de = (hi_e - lo_e) / (n_e - 1) if n_e > 1 else 0.0
    dr = (hi_r - lo_r) / (n_r - 1) if n_r > 1 else 0.0
    nbe = (n_e + BLOCK - 1) // BLOCK
    nbr = (n_r + BLOCK - 1) // BLOCK
    for a in range(n_e):
        CS[a, 2] = 0.0
    # the first maximiser so far: the largest margin, the first in scan order (k) among equal ones
    best, kbest, first = -np.inf, 0, 0
    for ia in range(nbe):
        a0, a1 = ia * BLOCK, min(n_e, (ia + 1) * BLOCK)
        ac = (a0 + a1 - 1) // 2
        _row_trig(gamma, lo_e, hi_e, n_e, ac, CS)
        for ib in range(nbr):
            b0, b1 = ib * BLOCK, min(n_r, (ib + 1) * BLOCK)
            bc = (b0 + b1 - 1) // 2
            m = _margin_cs(bx0, by0, bz0, bx1, by1, bz1, CS[ac, 0], CS[ac, 1], _lin(lo_r, hi_r, n_r, bc), hb,
                           lmin, lmax)
            k = ac * n_r + bc
            if m > best or (m == best and k < kbest):
                best, kbest, first = m, k, ia * nbr + ib
            # the carriage joint moves by at most |d rho| + sqrt(rho^2 + hb^2) |d eta| from the centre
            big = max(abs(_lin(lo_r, hi_r, n_r, b0)), abs(_lin(lo_r, hi_r, n_r, b1 - 1)))
            UB[ia * nbr + ib] = (m + max(bc - b0, b1 - 1 - bc) * dr
                                 + max(ac - a0, a1 - 1 - ac) * de * math.sqrt(big * big + hb * hb))
    for t in range(-1, nbe * nbr):
        blk = first if t < 0 else t
        if (t >= 0 and t == first) or UB[blk] < best - _SLACK:
            continue
        ia = blk // nbr
        ib = blk - ia * nbr
        a0, a1 = ia * BLOCK, min(n_e, (ia + 1) * BLOCK)
        b0, b1 = ib * BLOCK, min(n_r, (ib + 1) * BLOCK)
        ac, bc = (a0 + a1 - 1) // 2, (b0 + b1 - 1) // 2
        for a in range(a0, a1):
            _row_trig(gamma, lo_e, hi_e, n_e, a, CS)
            for b in range(b0, b1):
                if a == ac and b == bc:
                    continue
                m = _margin_cs(bx0, by0, bz0, bx1, by1, bz1, CS[a, 0], CS[a, 1], _lin(lo_r, hi_r, n_r, b), hb,
                               lmin, lmax)
                k = a * n_r + b
                if m > best or (m == best and k < kbest):
                    best, kbest = m, k
    return kbest // n_r, kbest % n_r


@njit(cache=True)
def best_carriage(bx0, by0, bz0, bx1, by1, bz1, gamma, e_lo, e_hi, r_lo, r_hi, hb, lmin, lmax, CS, UB, bounded):
    """The full search (module docstring): returns (rho, eta_rad). ``bounded``: each grid by
    :func:`bounded_argmax` (the same result), else by :func:`scan_argmax`."""
    lo_e, hi_e, lo_r, hi_r = e_lo, e_hi, r_lo, r_hi
    n_e = 1 if hi_e <= lo_e else _NE
    n_r = 1 if hi_r <= lo_r else _NR
    be, br = 0.5 * (e_lo + e_hi), 0.5 * (r_lo + r_hi)
    for _ in range(3):
        if bounded:
            ke, kr = bounded_argmax(bx0, by0, bz0, bx1, by1, bz1, gamma, lo_e, hi_e, n_e, lo_r, hi_r, n_r, hb, lmin,
                                    lmax, CS, UB)
        else:
            ke, kr = scan_argmax(bx0, by0, bz0, bx1, by1, bz1, gamma, lo_e, hi_e, n_e, lo_r, hi_r, n_r, hb, lmin,
                                 lmax)
        be = _lin(lo_e, hi_e, n_e, ke)
        br = _lin(lo_r, hi_r, n_r, kr)
        de = (hi_e - lo_e) / max(n_e - 1, 1)
        dr = (hi_r - lo_r) / max(n_r - 1, 1)
        lo_e, hi_e = max(e_lo, be - 2 * de), min(e_hi, be + 2 * de)
        lo_r, hi_r = max(r_lo, br - 2 * dr), min(r_hi, br + 2 * dr)
        n_e = 1 if hi_e <= lo_e else _NZ
        n_r = 1 if hi_r <= lo_r else _NZ
    return br, be


@njit(parallel=True, cache=True, nogil=True)
def resolve_kernel(points, u, e_lo, e_hi, r_lo, r_hi, hb, lmin, lmax, rho_out, eta_out, bounded):
    """The full search's carriage pose (``rho``, ``eta`` in radians) of each chain at each point;
    ``bounded``: each grid bounded by blocks (the same poses), else every point computed."""
    for p in prange(points.shape[0]):
        CS, UB = work_arrays()
        for i in range(3):
            g = 2.0 * math.pi * i / 3.0
            bx0, by0, bz0 = points[p, 0] + u[i, 0, 0], points[p, 1] + u[i, 0, 1], points[p, 2] + u[i, 0, 2]
            bx1, by1, bz1 = points[p, 0] + u[i, 1, 0], points[p, 1] + u[i, 1, 1], points[p, 2] + u[i, 1, 2]
            rho, eta = best_carriage(bx0, by0, bz0, bx1, by1, bz1, g, e_lo, e_hi, r_lo, r_hi, hb, lmin, lmax, CS, UB,
                                     bounded)
            rho_out[p, i] = rho
            eta_out[p, i] = eta
