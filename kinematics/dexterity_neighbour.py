"""Dexterity field by neighbour continuation: each voxel's carriage pose is climbed to a local maximum
of the resolver's margin from the carriage pose chosen at the voxel before it, and checked against
the full search on a sample with a stated tolerance.

Definition
----------
The resolver's criterion for chain ``i`` at a position ``P`` is the chain margin
``m_i(P; eta, rho) = min_j min(l_j - l_min, l_max - l_j)`` (:mod:`kinematics.carriage_search`);
the **full search** (``search="full"`` / ``"sweep"``) takes its first maximiser over a 73 x 61 grid
on the strokes and two 21 x 21 zooms (spacings ``s0 = (de, dr)`` = the coarse grid's, ``s0/5``,
``s0/25``).

The **neighbour search** (``search="neighbour"``) visits the voxels of one ``x`` plane in the sweep's
serpentine ``(y, z)`` order (so consecutive voxels are neighbours except across a gap). The first
voxel of a plane gets the full search. Every later voxel, per chain, starts at the carriage pose
chosen at the voxel before it and **climbs coarse to fine**: at the steps ``s0``, ``s0/5``, ``s0/25``
it moves ``eta`` by one step while the *profile* ``max_rho m_i(eta, rho)`` strictly grows, each
profile value found by the same 1-D ascent in ``rho`` from the current ``rho`` (so a ridge of the
margin in any direction is followed, which an ascent over the 8 grid neighbours is not); it stops at
a local maximum of ``m_i`` on the full search's finest spacing. **Start level**: a chain whose pose
moved by less than one coarse step (``max(|delta eta| / de, |delta rho| / dr) < 1``) from the voxel
before the previous one to the previous one starts at ``s0/5`` (its optimum moves little from voxel
to voxel there, and the coarse level's probes, 16 of a climb's 37 margins when nothing moves, find
nothing); one that moved further, or the first climb of a plane, starts at ``s0``. (Issue 24's
last round: every climb started at ``s0``; at ``h = 2`` a climb took 56 margins on average, now 47.
Starting every climb at ``s0/5`` took 57: the climbs that must travel walk at the fine step, 355
margins at the 99th percentile.) The margin can have several local
maxima, and the one followed from the neighbour can be overtaken by another: so a second climb
starts from the best point of a 13 x 11 scan of the strokes when that point's margin exceeds the
first climb's maximum, and the larger of the two maxima is kept (the neighbour's on a tie). (Until
issue 24's last round it started whenever that point came within 2 length units of the first
climb's maximum: 99.8 % of the chains at the default design's voxels climbed twice, and 88 % of the
second climbs started within one scan cell of the first's maximum and ended at it; the margin given
up by the stricter trigger is within the tolerance below, as measured there.) The scan skips the
points whose Lipschitz bound (:mod:`kinematics.carriage_search`: the margin where last computed plus
the path length walked since) is below that trigger: they can neither trigger the second climb nor
be its start, so the decisions and the poses are those of the scan of every point
(``bounded=False``, checked bit for bit by the tests). ``1/kappa`` of eq. (26) is then computed at
that pose as :mod:`kinematics.dexterity_sweep` does.

**Mirror.** Where the design, the orientation and the grid are symmetric under ``y -> -y``
(:func:`mirror_rows`: zero orientation, centred arc range, symmetric y centres and occupancy, and
platform joints that are mirror images: chain 1 onto itself with its legs swapped, chain 2 onto
chain 3), the search runs on the rows up to ``y = 0`` only (the same arrays there as the search of
the whole grid) and every other voxel takes its mirror voxel's pose, mirrored: the same ``d``, ``eta``
negated, chains 2 and 3 swapped. The mirrored pose has the same chain margins and the same
``1/kappa`` at the mirrored voxel (a reflection maps the legs onto the legs, so the leg lengths and
the singular values of ``J`` are those of the mirror voxel; both checked independently by the tests),
so the tolerance below holds for it exactly when it holds for the mirror voxel. This halves the
work, as the engine's mirror does.

**Tolerance** (stated; checked at run time and by the tests). With ``m_i^full`` the full search's
margin and ``m_i^nb`` the neighbour search's at the same voxel, the *margin gap* of a voxel is
``g = max_i (m_i^full - m_i^nb)`` (length units; negative where the climb found more margin than the
full search's grid). The neighbour search is within tolerance when ``g <= epsilon`` at every voxel,
``epsilon`` = :data:`MARGIN_TOLERANCE` (2 length units by default; the ``margin_tolerance``
argument). What that means for ``1/kappa``: the chosen carriage pose keeps every leg within
``epsilon`` of the largest margin the resolver can keep, i.e. it is an equally valid resolution of
the redundancy to within ``epsilon``; ``1/kappa`` is **not** bounded by it, because the margin has
flat ridges (about a quarter of the carriage grid within 2 mm of the maximum) along which ``J``
changes. The run-time check therefore reports, on its sample, the largest ``|1/kappa - 1/kappa_full|``
and the difference of the sample's GCI as well. Measured at ``h = 4`` against the full search at
every voxel (three designs: the default, ``a=30, b=20, eta_s=60`` at orientation (8, -5, 3) and
``d_s=80, eta_s=45``; 80,018 / 83,850 / 141,086 voxels): margin gap median <= 0.0024, 99 % 0.15 /
0.17 / 0.28, largest 0.90 / 1.12 / 1.10; ``|delta 1/kappa|`` median <= 5.5e-6, 99 % <= 1.3e-3,
largest 3.9e-3 / 1.1e-2 / 6.6e-3 (1/kappa itself is up to about 0.012); the GCI -0.16 %, +0.28 %,
-0.41 %. (Every climb from ``s0``: gap 99 % 0.14 / 0.16 / 0.27, largest 0.86 / 1.13 / 1.10, GCI
-0.16 %, +0.41 %, -0.47 %; with the former trigger of the second climb: gap 99 % <= 0.09, largest
0.58 / 1.72 / 1.25; GCI 0.2 %, 0.02 %, 0.5 %.)

**Run-time check**: a fixed, seeded sample of the reachable voxels (:data:`SAMPLE_FRACTION` of them,
at least :data:`SAMPLE_MIN` and at most :data:`SAMPLE_MAX`, all when fewer; a sample of 2,000 misses
a share ``p`` of voxels out of tolerance with probability ``(1 - p)^2000``, 13 % for ``p`` = 0.1 %)
is run through the full search
(:func:`kinematics.dexterity.resolved_carriages`, ``1/kappa`` by the field's own compiled eigenvalues:
:func:`kinematics.dexterity_sweep.inverse_condition_at`); the result reports the sample
size, the largest margin gap, the largest ``|delta 1/kappa|`` and the GCI difference on the sample,
and, when the largest gap exceeds ``epsilon``, ``tolerance_held = False`` with a message the CLI
prints. A check that passes on the sample does not prove the bound at every voxel.

Cost: per chain and voxel, a climb of about 47 margins and a restart scan of about 4.4 (the 13 x 11
scan's points are skipped when either of two upper bounds of their margin is below the trigger: the
Lipschitz bound above, and the first-order bound of the term that was the margin when last computed,
its gradient times the move since plus the leg's curvature bound; both are taken for all 143 points
in one branch-free pass) instead of the full search's 5,300, then ``1/kappa``
(:mod:`kinematics.dexterity_sweep`), on half the grid where the mirror holds, and the sample check
(at most 2,000 full searches, bounded by blocks: :mod:`kinematics.carriage_search`, about 22 us
each instead of 95 us; the first voxel of a plane uses the same bounded search). At ``h = 2``
(640,014 voxels, 2 cores, load 1.0-1.4): the whole field with its check takes 652-671 ms, 18.8-19.9x
the engine's 33-36 ms (724-746 ms, 21-22.5x, with the QL eigenvalues of ``1/kappa`` in the same
session, on fresh numba caches; 20.15x in ``benchmarks/bench_workspace.py --throughput`` at load
2.1; a later round made the engine 5-11 % faster and this field 6-9 % faster, 521-554 ms: 21.7-23.0x
the engine's 23-24 ms, above the 20x target; then 0.95-0.96 of that with the climb's step sines
taken once per field and the planes dealt to the threads, :mod:`kinematics.slices`: 510 ms, 21.6x
the engine's 24 ms at load 1.07; then, with the scan's tables passed whole, the check's ``1/kappa``
compiled and the field written in one pass, 501 ms, 20.7x at load 1.33; then, with the climb's
start level chosen by the chain's last move (0.92-0.93 alone) and 1/kappa taking the climb's own
cosines (0.98-1.0 alone), 540 -> 482 ms, 21.3x -> 19.1x the engine's 25.3 ms, before and after
alternating in one process at load 1.15, and 20.8-22.4x in three runs of the benchmark's row at load
1.5-1.8, whose engine is now timed in runs that follow an engine run; above the 20x target); it was
73-102x before the mirror, the 6 x 6 ``1/kappa``, the stricter restart trigger and the scan's
first-order bounds (measured one by one in issue 24's closing notes). The exact sweep is 297x and
the full search 325x in the same run.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Sequence

import numpy as np
from numba import njit, prange

from .carriage_search import _NE, _NR, _SLACK, _lin, _margin_cs, best_carriage, chain_legs, work_arrays
from .design import Design
from .dexterity_sweep import (
    _constants,
    _inverse_condition,
    by_planes,
    field_inputs,
    plane_costs,
    plane_index,
    plane_offsets,
)
from .parallel import kernel_launch
from .progress import CancelToken, Reporter
from .settings import DEXTERITY

#: Default ``epsilon`` of the stated tolerance on the margin gap (length units, module docstring;
#: its range: :data:`kinematics.settings.DEXTERITY`).
MARGIN_TOLERANCE = float(DEXTERITY["margin_tolerance"].default)
#: Share of the reachable voxels run through the full search at run time, the least number and the
#: most (about 0.1 s of the full search on 2 cores).
SAMPLE_FRACTION, SAMPLE_MIN, SAMPLE_MAX = 0.01, 50, 2000
#: Seed of the run-time sample (fixed: the same voxels for the same workspace).
SAMPLE_SEED = 24
#: Refinement factor between the climb's steps (the full search's zoom factor: 4 cells -> 20).
_ZOOM = 5.0
#: Climb levels: s0, s0/5, s0/25.
_LEVELS = 3
#: The coarse scan of the second start: _CE x _CR points on the strokes; it is climbed from when its
#: best margin exceeds the neighbour's climb's maximum.
_CE, _CR = 13, 11
#: The start level's rule (module docstring): a chain whose pose moved by less than
#: ``_NEAR_MOVE`` coarse steps at the voxel before starts its climb at level ``_NEAR_START``
#: (``s0/5``); one that moved further, or a plane's first climb, at level 0 (``s0``).
_NEAR_MOVE, _NEAR_START = 1.0, 1
#: Moves allowed per level (a safeguard; a climb on a stroke grid never needs this many).
_MAX_MOVES = 100000


@njit(cache=True, forceinline=True)
def _clamp(v, lo, hi):
    return lo if v < lo else (hi if v > hi else v)


@njit(cache=True, forceinline=True)
def _march(bx0, by0, bz0, bx1, by1, bz1, c, s, hb, lmin, lmax, r_lo, r_hi, r, m, sr):
    """1-D ascent in ``rho`` at one step ``sr``: from ``(r, m)`` towards the better side while the
    margin strictly grows. Returns ``(r, m)``."""
    if sr <= 0.0:
        return r, m
    ru = _clamp(r + sr, r_lo, r_hi)
    mu = _margin_cs(bx0, by0, bz0, bx1, by1, bz1, c, s, ru, hb, lmin, lmax)
    rd = _clamp(r - sr, r_lo, r_hi)
    md = _margin_cs(bx0, by0, bz0, bx1, by1, bz1, c, s, rd, hb, lmin, lmax)
    if mu > m and mu >= md:
        step, r, m = sr, ru, mu
    elif md > m:
        step, r, m = -sr, rd, md
    else:
        return r, m
    for _ in range(_MAX_MOVES):
        rn = _clamp(r + step, r_lo, r_hi)
        mn = _margin_cs(bx0, by0, bz0, bx1, by1, bz1, c, s, rn, hb, lmin, lmax)
        if mn > m:
            r, m = rn, mn
        else:
            break
    return r, m


@njit(cache=True, forceinline=True)
def _profile(bx0, by0, bz0, bx1, by1, bz1, c, s, hb, lmin, lmax, r_lo, r_hi, r, sr, levels):
    """The best ``rho`` at the arc angle whose ``gamma + eta`` has cosine ``c`` and sine ``s``, by 1-D
    ascent from ``r``, ``levels`` steps from ``sr`` down by :data:`_ZOOM`. Returns ``(r, m)``."""
    m = _margin_cs(bx0, by0, bz0, bx1, by1, bz1, c, s, r, hb, lmin, lmax)
    for _lev in range(levels):
        r, m = _march(bx0, by0, bz0, bx1, by1, bz1, c, s, hb, lmin, lmax, r_lo, r_hi, r, m, sr)
        sr /= _ZOOM
    return r, m


@njit(cache=True)
def _climb(bx0, by0, bz0, bx1, by1, bz1, gamma, e_lo, e_hi, r_lo, r_hi, hb, lmin, lmax, e, r, trig, start):
    """Coarse-to-fine ascent of the chain margin from ``(eta, rho) = (e, r)`` (module docstring):
    in ``eta`` over the profile ``max_rho m`` (each ``rho`` re-climbed from the current one, so a
    ridge in any direction is followed), from level ``start`` (0: the step ``s0``; 1: ``s0/5``) to
    the finest. Returns ``(rho, eta_rad, margin, cos, sin)`` (the last two: of ``gamma + eta``, as
    the climb holds them; 1/kappa takes them). The cosine and sine of ``gamma + eta`` at a step of
    ``eta`` come from those at the current ``eta`` by the angle-addition formulas (computed directly
    where the step is cut at a stroke end); those of the step at each level are ``trig``
    (:func:`_step_trig`: the same for every climb of a field, so taken once)."""
    se = (e_hi - e_lo) / (_NE - 1) if e_hi > e_lo else 0.0
    sr = (r_hi - r_lo) / (_NR - 1) if r_hi > r_lo else 0.0
    e = _clamp(e, e_lo, e_hi)
    r = _clamp(r, r_lo, r_hi)
    c, s = math.cos(gamma + e), math.sin(gamma + e)
    for _lev in range(start):
        se /= _ZOOM
        sr /= _ZOOM
    r, m = _profile(bx0, by0, bz0, bx1, by1, bz1, c, s, hb, lmin, lmax, r_lo, r_hi, r, sr, _LEVELS - start)
    for lev in range(start, _LEVELS):
        if se > 0.0:
            cd, sd = trig[2 * lev], trig[2 * lev + 1]
            direction = 0.0
            for _ in range(_MAX_MOVES):
                best, be, br, bc, bs = m, e, r, c, s
                for sg in (-1.0, 1.0):
                    if direction != 0.0 and sg != direction:
                        continue
                    ee = e + sg * se
                    if e_lo <= ee <= e_hi:
                        cc, ss = c * cd - sg * s * sd, s * cd + sg * c * sd
                    else:
                        ee = _clamp(ee, e_lo, e_hi)
                        cc, ss = math.cos(gamma + ee), math.sin(gamma + ee)
                    rr, mm = _profile(bx0, by0, bz0, bx1, by1, bz1, cc, ss, hb, lmin, lmax, r_lo, r_hi, r, sr,
                                      _LEVELS - lev)
                    if mm > best:
                        best, be, br, bc, bs = mm, ee, rr, cc, ss
                        direction = sg
                if best > m:
                    m, e, r, c, s = best, be, br, bc, bs
                else:
                    break
        se /= _ZOOM
        sr /= _ZOOM
    return r, e, m, c, s


@njit(cache=True)
def _step_trig(e_lo, e_hi):
    """The cosine and sine of :func:`_climb`'s step in ``eta`` at each of its levels, as
    ``(cos s_0, sin s_0, cos s_1, sin s_1, cos s_2, sin s_2)`` (the steps as :func:`_climb` takes
    them, so the same numbers bit for bit)."""
    se = (e_hi - e_lo) / (_NE - 1) if e_hi > e_lo else 0.0
    c0, s0 = math.cos(se), math.sin(se)
    se /= _ZOOM
    c1, s1 = math.cos(se), math.sin(se)
    se /= _ZOOM
    return (c0, s0, c1, s1, math.cos(se), math.sin(se))


@njit(cache=True)
def _coarse_best(bx0, by0, bz0, bx1, by1, bz1, gamma, e_lo, e_hi, r_lo, r_hi, hb, lmin, lmax):
    """First maximiser ``(eta, rho, margin)`` of the margin on the :data:`_CE` x :data:`_CR` scan of
    the strokes."""
    n_e = 1 if e_hi <= e_lo else _CE
    n_r = 1 if r_hi <= r_lo else _CR
    best, be, br = -np.inf, e_lo, r_lo
    for a in range(n_e):
        e = _lin(e_lo, e_hi, n_e, a)
        c, s = math.cos(gamma + e), math.sin(gamma + e)
        for b in range(n_r):
            r = _lin(r_lo, r_hi, n_r, b)
            m = _margin_cs(bx0, by0, bz0, bx1, by1, bz1, c, s, r, hb, lmin, lmax)
            if m > best:
                best, be, br = m, e, r
    return be, br, best


@njit(cache=True)
def _scan_rows(gamma, e_lo, e_hi, CS):
    """``CS[a] = (cos, sin)`` of ``gamma + eta`` at row ``a`` of the restart scan (as
    :func:`_coarse_best` computes them)."""
    n_e = 1 if e_hi <= e_lo else _CE
    for a in range(n_e):
        e = _lin(e_lo, e_hi, n_e, a)
        CS[a, 0], CS[a, 1] = math.cos(gamma + e), math.sin(gamma + e)


@njit(cache=True, forceinline=True)
def _margin_grad(bx0, by0, bz0, bx1, by1, bz1, c, s, rho, hb, lmin, lmax):
    """:func:`kinematics.carriage_search._margin_cs` (the same value, bit for bit) with the active
    term's gradient in the platform's ``y`` and ``z`` and its leg length: ``(m, gy, gz, l, convex)``;
    ``convex`` when the active term is ``l - l_min`` (convex in the position), not ``l_max - l``."""
    dy0, l0, dy1, l1 = chain_legs(bx0, by0, bz0, bx1, by1, bz1, c, s, rho, hb)
    m = min(min(l0 - lmin, lmax - l0), min(l1 - lmin, lmax - l1))
    if m == l0 - lmin:
        return m, dy0 / l0, bz0 / l0, l0, True
    if m == lmax - l0:
        return m, -dy0 / l0, -bz0 / l0, l0, False
    if m == l1 - lmin:
        return m, dy1 / l1, bz1 / l1, l1, True
    return m, -dy1 / l1, -bz1 / l1, l1, False


@njit(cache=True, forceinline=True)
def _coarse_best_bounded(bx0, by0, bz0, bx1, by1, bz1, gamma, e_lo, e_hi, r_lo, r_hi, hb, lmin, lmax, ST, D,
                         thr, CS, T, py, pz, need, c):
    """:func:`_coarse_best` with its scan points pruned by two upper bounds of their margin at the
    voxel ``(py, pz)`` of the plane, from what ``T[:, k]`` keeps of point ``k``'s last computation
    (its margin ``m``, the gradient in ``y`` and ``z`` of the term that was the margin, that term's
    leg length ``l``, 1 when the term is ``l - l_min`` else 0, and ``y``, ``z`` and the path length
    ``D`` walked then; ``ST[0] == 1``: the bounds are set): the Lipschitz bound of
    :mod:`kinematics.carriage_search`, ``m`` plus the path walked since, and the first-order bound of
    the term that was the margin: with ``Delta`` the move since, the term is at most
    its value plus ``grad . Delta``, plus ``|Delta|^2 / (2 (l - |Delta|))`` for ``l - l_min`` (the leg
    length is convex with Hessian ``(I - n n^T) / l``, and ``|Delta|`` is at most the path walked),
    and the margin, the least term, is at most any term. A point whose bound is below ``thr - 1e-7``
    has a margin below ``thr`` and is skipped. The bounds are taken for every point in one pass
    without branches (``need``: scratch), then the points left are computed in scan order. The caller
    climbs again only when the result's margin exceeds ``thr``: then the skipped points are below
    the maximum, so the first maximiser and the decision are :func:`_coarse_best`'s; otherwise the
    margin returned is a value ``<= thr`` (``-inf`` when every point was skipped). ``CS[a]``: the
    cosine and sine of ``gamma + eta`` of row ``a`` (:func:`_scan_rows`). Inlined, with
    :func:`kinematics.dexterity_sweep._inverse_condition`, for the reference counts of its array
    arguments (measured there); the kernel's tables are passed whole with the chain ``c`` (``ST[c]``,
    ``CS[c]``, ``T[c]``), since a view of one costs two atomic reference counts per chain and voxel."""
    n_e = 1 if e_hi <= e_lo else _CE
    n_r = 1 if r_hi <= r_lo else _CR
    n = n_e * n_r
    valid = ST[c, 0] == 1.0
    t = thr - _SLACK - D
    t1 = thr - _SLACK
    left = n
    if valid:
        left = 0
        for k in range(n):
            room = T[c, 3, k] - (D - T[c, 7, k])
            ddy = py - T[c, 5, k]
            ddz = pz - T[c, 6, k]
            # bound >= t1 with the curvature term's division multiplied out (room > 0)
            below = (t1 - T[c, 0, k] - T[c, 1, k] * ddy - T[c, 2, k] * ddz) * (2.0 * room)
            need[k] = (T[c, 0, k] - T[c, 7, k] >= t) & ((room <= 0.0)
                                                        | (below <= T[c, 4, k] * (ddy * ddy + ddz * ddz)))
            left += need[k]
    best, be, br = -np.inf, e_lo, r_lo
    for k in range(n):
        if left == 0:
            break
        if valid and not need[k]:
            continue
        left -= 1
        a = k // n_r
        b = k - a * n_r
        e = _lin(e_lo, e_hi, n_e, a)
        r = _lin(r_lo, r_hi, n_r, b)
        m, gy, gz, ll, convex = _margin_grad(bx0, by0, bz0, bx1, by1, bz1, CS[c, a, 0], CS[c, a, 1], r, hb, lmin,
                                             lmax)
        T[c, 0, k], T[c, 1, k], T[c, 2, k], T[c, 3, k] = m, gy, gz, ll
        T[c, 4, k] = 1.0 if convex else 0.0
        T[c, 5, k], T[c, 6, k], T[c, 7, k] = py, pz, D
        if m > best:
            best, be, br = m, e, r
    ST[c, 0] = 1.0
    return be, br, best


@njit(parallel=True, cache=True, nogil=True)
def _neighbour_kernel(occ, planes, offset, xs, ys, zs, u, R2, e_lo, e_hi, r_lo, r_hi, hb, inv_L, lmin, lmax,
                      out, rho_out, eta_out, margin_out, bounded):
    """The neighbour search (module docstring) over the ``x`` planes ``planes`` (``-1``: none): ``out`` gets
    ``1/kappa``, ``rho_out``/``eta_out``/``margin_out`` (N, 3; ``rho = r - d``, ``eta`` in radians)
    the chosen carriage and its chain margins, for the reachable voxels in C order. ``bounded``: the
    restart scan pruned by the Lipschitz bounds (:func:`_coarse_best_bounded`; the same poses), else
    every scan point computed (:func:`_coarse_best`, the reference the tests compare with)."""
    ny, nz = occ.shape[1], occ.shape[2]
    for t in prange(planes.shape[0]):
        i = planes[t]
        if i < 0:
            continue
        CS, UB = work_arrays()
        rho = np.zeros(3)
        eta = np.zeros(3)
        A = np.empty((6, 18))
        G = np.empty((6, 6))
        CST = np.zeros((3, 1))
        CCS = np.empty((3, _CE, 2))
        CT = np.empty((3, 8, _CE * _CR))
        CNEED = np.empty(_CE * _CR, np.bool_)
        CSV = np.empty((3, 2))  # the chains' carriage angles' cosines and sines, for 1/kappa
        for c in range(3):
            _scan_rows(2.0 * math.pi * c / 3.0, e_lo, e_hi, CCS[c])
        trig = _step_trig(e_lo, e_hi)
        # each chain's last move in coarse steps (the larger of eta's and rho's); a plane's first
        # climbs start at the coarse level
        moved = np.full(3, np.inf)
        inv_se = (_NE - 1) / (e_hi - e_lo) if e_hi > e_lo else 0.0
        inv_sr = (_NR - 1) / (r_hi - r_lo) if r_hi > r_lo else 0.0
        index = plane_index(occ, i, ny, offset[i])
        px = xs[i]
        first = True
        D = 0.0  # path length walked in the plane (the Lipschitz bounds' running sum)
        qy, qz = 0.0, 0.0
        for j in range(ny):
            py = ys[j]
            for kk in range(nz):
                k = kk if j % 2 == 0 else nz - 1 - kk
                if not occ[i, j, k]:
                    continue
                pz = zs[k]
                if not first:
                    D += math.sqrt((py - qy) ** 2 + (pz - qz) ** 2)
                qy, qz = py, pz
                m = index[j, k]
                for c in range(3):
                    g = 2.0 * math.pi * c / 3.0
                    bx0, by0, bz0 = px + u[c, 0, 0], py + u[c, 0, 1], pz + u[c, 0, 2]
                    bx1, by1, bz1 = px + u[c, 1, 0], py + u[c, 1, 1], pz + u[c, 1, 2]
                    if first:  # no previous pose: the full search
                        r, e = best_carriage(bx0, by0, bz0, bx1, by1, bz1, g, e_lo, e_hi, r_lo, r_hi, hb,
                                             lmin, lmax, CS, UB, True)
                        cc, ss = math.cos(g + e), math.sin(g + e)
                        mg = _margin_cs(bx0, by0, bz0, bx1, by1, bz1, cc, ss, r, hb, lmin, lmax)
                    else:
                        # a chain whose pose moved less than one coarse step at the voxel before
                        # starts at the second level (module docstring)
                        start = 0 if moved[c] >= _NEAR_MOVE else _NEAR_START
                        r, e, mg, cc, ss = _climb(bx0, by0, bz0, bx1, by1, bz1, g, e_lo, e_hi, r_lo, r_hi, hb,
                                                  lmin, lmax, eta[c], rho[c], trig, start)
                        # a second start at the best of a coarse scan of the strokes: another local
                        # maximum may have overtaken the one followed from the neighbour
                        if bounded:
                            ce, cr, cm = _coarse_best_bounded(bx0, by0, bz0, bx1, by1, bz1, g, e_lo, e_hi, r_lo,
                                                              r_hi, hb, lmin, lmax, CST, D, mg,
                                                              CCS, CT, py, pz, CNEED, c)
                        else:
                            ce, cr, cm = _coarse_best(bx0, by0, bz0, bx1, by1, bz1, g, e_lo, e_hi, r_lo, r_hi, hb,
                                                      lmin, lmax)
                        if cm > mg:
                            r2, e2, m2, c2, s2 = _climb(bx0, by0, bz0, bx1, by1, bz1, g, e_lo, e_hi, r_lo, r_hi,
                                                        hb, lmin, lmax, ce, cr, trig, 0)
                            if m2 > mg:
                                r, e, mg, cc, ss = r2, e2, m2, c2, s2
                    if not first:
                        moved[c] = max(abs(e - eta[c]) * inv_se, abs(r - rho[c]) * inv_sr)
                    rho[c] = r
                    eta[c] = e
                    CSV[c, 0], CSV[c, 1] = cc, ss
                    rho_out[m, c] = r
                    eta_out[m, c] = e
                    margin_out[m, c] = mg
                first = False
                out[m] = _inverse_condition(px, py, pz, u, R2, rho, CSV, hb, inv_L, A, G)


@njit(parallel=True, cache=True, nogil=True)
def _margins_kernel(points, u, rho, eta, hb, lmin, lmax, out):
    """Chain margins (N, 3) at per-point carriages ``rho`` and ``eta`` (N, 3, radians)."""
    for p in prange(points.shape[0]):
        for c in range(3):
            v = 2.0 * math.pi * c / 3.0 + eta[p, c]
            out[p, c] = _margin_cs(points[p, 0] + u[c, 0, 0], points[p, 1] + u[c, 0, 1], points[p, 2] + u[c, 0, 2],
                                   points[p, 0] + u[c, 1, 0], points[p, 1] + u[c, 1, 1], points[p, 2] + u[c, 1, 2],
                                   math.cos(v), math.sin(v), rho[p, c], hb, lmin, lmax)


def chain_margins(design: Design, points: np.ndarray, d: np.ndarray, eta_deg: np.ndarray,
                  orientation: Sequence[float] = (0.0, 0.0, 0.0)) -> np.ndarray:
    """The resolver's chain margins ``m_i`` (N, 3) at positions ``points`` (N, 3) of one orientation
    with per-point carriages ``d`` and ``eta_deg`` (N, 3 each)."""
    pts = np.ascontiguousarray(np.asarray(points, float).reshape(-1, 3))
    n = pts.shape[0]
    rho = np.ascontiguousarray(design.r - np.asarray(d, float).reshape(n, 3))
    eta = np.ascontiguousarray(np.radians(np.asarray(eta_deg, float).reshape(n, 3)))
    u, _R2, hb, _ = _constants(design, orientation)
    out = np.zeros((n, 3))
    if n:
        with kernel_launch(n):
            _margins_kernel(pts, u, rho, eta, hb, float(design.l_min), float(design.l_max), out)
    return out


#: The mirror ``y -> -y``: chain 1 onto itself, chains 2 and 3 swapped (indices 0, 2, 1).
_MIRROR_CHAINS = np.array([0, 2, 1])


def mirror_rows(design: Design, occupancy: np.ndarray, axes: Sequence[np.ndarray],
                orientation: Sequence[float]) -> int | None:
    """The rows ``j < ny_eval`` of ``occupancy`` that determine the field by the mirror ``y -> -y``
    (module docstring, "Mirror"), or None where the mirror does not hold exactly: the orientation is
    zero, the arc range centred, the y centres and the occupancy symmetric, and the platform joints
    mirror images of each other (leg 1 of chain 1 onto its leg 2, chain 2's legs onto chain 3's)."""
    occ = np.asarray(occupancy, bool)
    ys = np.asarray(axes[1], float)
    h = float(ys[1] - ys[0]) if ys.size > 1 else 1.0
    if (design.eta_range != "centered" or any(float(a) != 0.0 for a in orientation) or ys.size < 2
            or not np.allclose(ys, -ys[::-1], rtol=0.0, atol=1e-9 * max(1.0, abs(h)))
            or not np.array_equal(occ, occ[:, ::-1, :])):
        return None
    u = _constants(design, orientation)[0]
    flip = np.array([1.0, -1.0, 1.0])
    scale = 1e-12 * max(1.0, float(np.abs(u).max()))
    if not np.allclose(u[_MIRROR_CHAINS][:, ::-1] * flip, u, rtol=0.0, atol=scale):
        return None
    return (ys.size + 1) // 2


@njit(parallel=True, cache=True, nogil=True)
def _mirror_fill_kernel(occ, ny_eval, offset, perm, vals, rho, eta, margin):
    """:func:`neighbour_field`'s mirror, in place: each reachable voxel of a row ``j >= ny_eval`` of
    ``occ`` takes its mirror voxel's (row ``ny - 1 - j``) ``1/kappa``, its chains' ``rho`` and margins
    with chains 2 and 3 swapped (``perm``: :data:`_MIRROR_CHAINS`) and their ``eta`` negated (arrays
    over the reachable voxels of ``occ`` in C order; ``offset[i]``: the index of plane ``i``'s first)."""
    nx, ny, nz = occ.shape
    for i in prange(nx):
        idx = plane_index(occ, i, ny, offset[i])
        for j in range(ny_eval, ny):
            for k in range(nz):
                if not occ[i, j, k]:
                    continue
                m = idx[j, k]
                h = idx[ny - 1 - j, k]
                vals[m] = vals[h]
                for c in range(3):
                    rho[m, c] = rho[h, perm[c]]
                    eta[m, c] = -eta[h, perm[c]]
                    margin[m, c] = margin[h, perm[c]]


def neighbour_field(design: Design, occupancy: np.ndarray, axes: Sequence[np.ndarray],
                    orientation: Sequence[float] = (0.0, 0.0, 0.0), progress: Reporter | None = None,
                    cancel: CancelToken = None, bounded: bool = True, mirror: bool = True
                    ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """``1/kappa`` at the neighbour search's carriage pose (module docstring) of every reachable voxel
    of ``occupancy`` in C order: ``(inverse_condition, d, eta_deg, margins)`` (margins: (N, 3)).
    ``bounded=False`` computes every point of the restart scan (the same result, slower: the
    reference of the tests). ``mirror``: where :func:`mirror_rows` holds, search the rows up to
    ``y = 0`` only and give every other voxel its mirror voxel's pose, mirrored (the same arrays on
    those rows as ``mirror=False``)."""
    out, rho, eta, margin = _search(design, occupancy, axes, orientation, progress, cancel, bounded, mirror)
    return out, design.r - rho, np.degrees(eta) + 0.0, margin


def neighbour_values(design: Design, occupancy: np.ndarray, axes: Sequence[np.ndarray],
                     orientation: Sequence[float] = (0.0, 0.0, 0.0), progress: Reporter | None = None,
                     cancel: CancelToken = None) -> tuple[np.ndarray, np.ndarray]:
    """:func:`neighbour_field`'s ``(inverse_condition, margins)`` alone (the dexterity field's needs:
    the carriage poses in ``d`` and degrees cost 8 ms at h = 2)."""
    out, _rho, _eta, margin = _search(design, occupancy, axes, orientation, progress, cancel, True, True)
    return out, margin


def _search(design: Design, occupancy: np.ndarray, axes: Sequence[np.ndarray], orientation: Sequence[float],
            progress: Reporter | None, cancel: CancelToken, bounded: bool, mirror: bool
            ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The neighbour search: ``(inverse_condition, rho, eta_rad, margins)`` over the reachable voxels
    of ``occupancy`` in C order (:func:`neighbour_field`)."""
    ny_eval = mirror_rows(design, occupancy, axes, orientation) if mirror else None
    occ = np.ascontiguousarray(np.asarray(occupancy, bool))
    offset, n = plane_offsets(occ)
    # the search on the rows it owns (those up to y = 0 under the mirror), written where they are in
    # the whole grid's C order (``offset``)
    rows = occ.shape[1] if ny_eval is None else ny_eval
    f = field_inputs(design, occ[:, :rows, :], (axes[0], axes[1][:rows], axes[2]), orientation)
    out = np.zeros(n)
    rho = np.zeros((n, 3))
    eta = np.zeros((n, 3))
    margin = np.zeros((n, 3))
    by_planes(plane_costs(f.occ), lambda planes: _neighbour_kernel(
        f.occ, planes, offset, f.xs, f.ys, f.zs, f.u, f.R2, f.e_lo, f.e_hi, f.r_lo, f.r_hi, f.hb, f.inv_L,
        float(design.l_min), float(design.l_max), out, rho, eta, margin, bool(bounded)), progress, cancel)
    if ny_eval is not None:
        with kernel_launch(occ.shape[0]):
            _mirror_fill_kernel(occ, ny_eval, offset, _MIRROR_CHAINS, out, rho, eta, margin)
    return out, rho, eta, margin


def sample_indices(n: int, fraction: float = SAMPLE_FRACTION, minimum: int = SAMPLE_MIN,
                   maximum: int = SAMPLE_MAX, seed: int = SAMPLE_SEED) -> np.ndarray:
    """The run-time check's sample of ``range(n)``: ``ceil(fraction n)`` indices, at least
    ``minimum`` and at most ``maximum`` (all when ``n`` is smaller), drawn without replacement with
    a fixed seed, sorted."""
    k = min(n, max(int(minimum), min(int(maximum), math.ceil(fraction * n))))
    return np.sort(np.random.default_rng(seed).choice(n, k, replace=False)) if k < n else np.arange(n)


@dataclasses.dataclass
class SampleCheck:
    """The run-time check of the neighbour search against the full search (module docstring)."""

    sample_size: int
    voxels: int
    margin_tolerance: float  # epsilon
    max_margin_gap: float  # largest max_i (m_i^full - m_i^nb) over the sample
    max_abs_delta_inverse_condition: float  # largest |1/kappa - 1/kappa_full| over the sample
    gci_difference: float  # mean 1/kappa - mean 1/kappa_full over the sample
    tolerance_held: bool
    message: str

    def to_dict(self) -> dict:
        return dataclasses.asdict(self)


def compare(vals: np.ndarray, margins: np.ndarray, full_vals: np.ndarray, full_margins: np.ndarray,
            voxels: int, margin_tolerance: float) -> SampleCheck:
    """:class:`SampleCheck` of a sample's neighbour-search values and margins against the full
    search's (arrays over the same sample voxels)."""
    n = int(vals.size)
    if n == 0:
        return SampleCheck(0, voxels, margin_tolerance, 0.0, 0.0, 0.0, True, "no reachable voxel to check")
    gap = float(np.max(full_margins - margins))
    dk = float(np.max(np.abs(vals - full_vals)))
    dg = float(vals.mean() - full_vals.mean())
    held = gap <= margin_tolerance
    what = (f"on {n} of {voxels} voxels checked against the full search, the largest margin gap is {gap:.3g} "
            f"(tolerance {margin_tolerance:g}), largest |delta 1/kappa| {dk:.3g}, GCI difference {dg:+.3g}")
    message = (what if held else
               f"dexterity tolerance broken: {what}; the neighbour search's carriage poses keep less leg margin "
               f"than the resolver's, rerun with --dexterity-search sweep for the exact poses")
    return SampleCheck(n, voxels, margin_tolerance, gap, dk, dg, held, message)
