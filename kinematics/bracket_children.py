"""The bracket's refinement step decided per parent cube: one pass over the parent's arc samples
tells each of its 8 children which samples need a test of their own.

A boundary cube (centre ``Pp``) is split into 8 children of half the edge, each with centre ``Pc``,
half-diagonal ``delta`` and ``|Pc - Pp| <= delta``. Each child decides each chain with
:func:`kinematics.blocks.decide_chain` (via :func:`kinematics.bracket._cube_chain`): the relaxed
test at ``Pc`` with ``e_r = delta + arc_slack + eps`` and the tight test with ``e_t = delta + eps``
at the samples of its window. For a fixed carriage pose ``(k, rho)`` every leg length is
1-Lipschitz in the platform position (:mod:`kinematics.blocks`), so with a safety margin ``s``
(half the rounding margin ``eps``, far above the rounding error of one test) the parent's centre,
tested ONCE per sample ``k`` with three limits, flags:

* ``R1`` (relaxation ``e_r + delta + s``) fails at ``Pp``  =>  no child passes the relaxed test at
  ``k`` (a child's ``(k, rho)`` would give ``Pp`` legs within ``delta`` of its own);
* ``R0`` (relaxation ``e_r - delta - s``) passes at ``Pp``  =>  every child passes the relaxed test
  at ``k`` (the same ``(k, rho)`` gives each child legs within ``delta`` of ``Pp``'s);
* ``X`` (tightening ``e_t - delta - s``) fails at ``Pp``  =>  no child passes the tight test at ``k``.

The parent skips whole sub-arcs of samples: where the whole-stroke bound of the sub-arc rejects
the chain at ``Pp`` with the ``R1`` limits (it is conservative over the continuous sub-arc), no
sample of it has ``R1``. The samples of the other sub-arcs get all three tests, in a loop without
branches over runs widened to whole SIMD registers (:func:`_flag_run`;
:func:`kinematics.feasibility._passes` answers exactly as the per-sample test, and only the
soundness of the flags, not their values, enters the children's decisions). The parent then lists
its samples by flag once (``X``; ``R0``; ``R1`` without ``R0``), and a child's searches walk these
lists in the window's order: the samples, tests and order of a scan that skips unflagged samples.

A child then evaluates (exactly as :func:`kinematics.blocks.decide_chain` does: the same
functions, limits and samples) only the samples these flags leave open: the relaxed test where
``R1`` passes and ``R0`` fails, and the tight test where ``X`` passes. Its decision does not depend
on the order in which its samples are visited -- OK iff the hint or a visited sample passes both
tests, FAIL iff the whole-stroke bound rejects or no visited sample passes the relaxed test, and on
UNKNOWN the window becomes the first and last visited samples that pass the relaxed test -- so it is
the same decision, window included, as the per-child path (``method="cubes"`` of
:func:`kinematics.bracket.refine_boundary`; tested child by child). Visited samples are those of
the window in sub-arcs the child's whole-stroke bound leaves open (every sample of the window when
it is narrower than a sub-arc), as there. Joint cones are not covered (their relaxation enters
each cone with its own factor): with cones the bracket takes the per-child path.

*Compile time.* numba inlines a function marked ``inline="always"`` into its caller's IR, and the
caller's passes (the parallel kernel's most of all) then run over every copy. The child's rarer tests
(the hint's, once per child and chain; the relaxed test of a sample that already passed the tight
one, at most once; the scan for the window's upper end, on the levels that keep windows), its
sub-arc bounds and the parent's flag pass are therefore functions of their own
(:func:`_feasible_call`, :func:`_sub_arc_open`, :func:`_parent_flags`), compiled once by numba and
inlined by LLVM (``forceinline=True``); the two scans that decide most children keep their tests
inlined by numba. numba's inlining of the rarer tests took the kernel's first compile to 87 s of one
core, against 37 s with them as calls (a fresh cache, the quiet 2-core machine) at the same speed;
LLVM's inlining of those calls (twenty-first round) took 0.93 of the bracket's time at h = 2,
refine 2 (389 against 417 ms, medians of seven processes of each alternating, load 1.2-1.6; the same
bracket) for 1.6 s more of the bracket's first compile. This module keeps numba's inlining for the
scans' tests where the rest of the package has LLVM's (:mod:`kinematics.warmup`): with LLVM's, its
kernel compiled in 5 s instead of 32 s, but the bracket measured slower where every other function
was pinned as a call (529-558 ms against 420-448 ms at h = 2, refine 2) and no faster where it was
not.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit, prange

from .blocks import FAIL, OK, UNKNOWN, _segment_open, _stroke_open
from .feasibility import _leg_frames, _passes, chain_points, cones_set, feasible_plain

__all__ = ["children_kernel", "has_cones"]

INSIDE, OUTSIDE, BOUNDARY = 1, 2, 0
#: Parents one thread decides with one set of scratch (:func:`children_kernel`).
_CHUNK = 64
#: Flags of a parent's sample (module docstring).
_R1, _R0, _X = 1, 2, 4
#: The flag pass's runs are whole multiples of this many samples (:func:`_flag_run`): eight doubles
#: fill one AVX-512 register (two AVX2 ones).
_LANES = 8


def has_cones(jc: np.ndarray) -> bool:
    """Whether any chain's tests include joint cones (:func:`kinematics.feasibility.cones_set`, as
    :func:`kinematics.feasibility._leg_sets` decides)."""
    return any(cones_set(np.ascontiguousarray(jc[i])) for i in range(jc.shape[0]))


@njit(cache=True, inline="always")
def _limits2(lo, hi):
    """Squared leg limits ``[lo, hi]`` clipped at 0 below (``lo2 > hi2`` when empty)."""
    lo = max(lo, 0.0)
    if lo > hi:
        return 1.0, 0.0
    return lo * lo, hi * hi


@njit(cache=True, inline="always")
def _flag_one(b1x, b1y, b1z, b2x, b2y, b2z, cos_t, sin_t, i, hb, rho_lo, rho_hi, l1, h1, l0, h0, lx, hx, k, flags):
    """The three tests of sample ``k`` of chain ``i``, into ``flags[i, k]``, without a branch; an empty
    limit pair (``lo2 > hi2``) never passes."""
    p1, _, q1, p2, _, q2 = _leg_frames(b1x, b1y, b1z, b2x, b2y, b2z, cos_t[i, k], sin_t[i, k], hb)
    f1 = _passes(p1, q1, p2, q2, l1, h1, rho_lo, rho_hi) & (l1 <= h1)
    f0 = _passes(p1, q1, p2, q2, l0, h0, rho_lo, rho_hi) & (l0 <= h0)
    fx = _passes(p1, q1, p2, q2, lx, hx, rho_lo, rho_hi) & (lx <= hx)
    flags[i, k] = np.uint8(f1) | (np.uint8(f1 & f0) << 1) | (np.uint8(f1 & fx) << 2)


@njit(cache=True, inline="always")
def _flag_run(b1x, b1y, b1z, b2x, b2y, b2z, cos_t, sin_t, i, hb, rho_lo, rho_hi, l1, h1, l0, h0, lx, hx, a, b,
              flags):
    """The three tests of every sample ``a..b`` of chain ``i``, into ``flags[i]``, in SIMD lanes. The
    run is first widened to a whole number of :data:`_LANES` samples (to the right, or to the left at
    the stroke's end), so that the vector loop leaves no scalar remainder: a run is a few samples to a
    few dozen (a last-level window holds 14-22 samples at the median), and each sample of the
    remainder was a scalar pass with twelve square roots. A sample the widening adds gets the flags
    of its own tests, which are as sound as any (the children read only the samples of their
    window)."""
    n = cos_t.shape[1]
    w = ((b - a + _LANES) // _LANES) * _LANES
    if w <= n:
        b = min(a + w - 1, n - 1)
        a = b - w + 1
    # unsigned sample indices: numba wraps a signed index that may be negative around the axis, and
    # LLVM then gathers the tables lane by lane instead of loading them (1.6x the time per sample)
    ua = np.uint64(a)
    for t in range(np.uint64(b - a + 1)):
        _flag_one(b1x, b1y, b1z, b2x, b2y, b2z, cos_t, sin_t, i, hb, rho_lo, rho_hi, l1, h1, l0, h0, lx, hx, ua + t,
                  flags)


@njit(cache=True, nogil=True, forceinline=True)
def _parent_flags(px, py, pz, u, i, cos_t, sin_t, seg_k, seg_arc, hb, rho_lo, rho_hi, lmin, lmax, klo, khi, r1, r0, x,
                  flags):
    """``flags[i, k]`` for (at least) the samples ``klo..khi`` of chain ``i`` at the parent's centre
    (module docstring). A sub-arc whose whole-stroke bound rejects the chain with the ``R1`` limits
    (conservative over the continuous sub-arc, ends included) has no ``R1`` sample: no test there;
    the samples of the other sub-arcs get all three tests, in runs (:func:`_flag_run`; the sub-arcs
    between two rejected ones in one run)."""
    b1x, b1y, b1z, b2x, b2y, b2z = chain_points(px, py, pz, u, i)
    l1, h1 = _limits2(lmin - r1, lmax + r1)
    l0, h0 = _limits2(lmin - r0, lmax + r0)
    lx, hx = _limits2(lmin + x, lmax - x)
    lo1, hi1 = max(lmin - r1, 0.0), lmax + r1
    n_seg = seg_k.shape[0]
    done = klo - 1  # samples up to here have their flags, or are in the pending run
    run = -1  # the first sample of the pending run (-1: none)
    # one step past the last sub-arc flushes the last run: the inlined vector loop has one call site
    for g in range(n_seg + 1):
        a = b = 0
        closed = False
        if g < n_seg:
            a, b = max(seg_k[g, 0], klo), min(seg_k[g, 1], khi)
            if b < a or b <= done:
                continue
            closed = b - a >= 3 and not _segment_open(b1x, b1y, b1z, b2x, b2y, b2z, hb, seg_arc, i, g, rho_lo,
                                                      rho_hi, lo1, hi1)
        if run >= 0 and (closed or g == n_seg):
            _flag_run(b1x, b1y, b1z, b2x, b2y, b2z, cos_t, sin_t, i, hb, rho_lo, rho_hi, l1, h1, l0, h0, lx, hx, run,
                      done, flags)
            run = -1
        if g == n_seg:
            break
        if closed:
            for k in range(a, b + 1):
                flags[i, k] = 0
        elif run < 0:
            run = max(a, done + 1)
        done = b


@njit(cache=True, nogil=True, forceinline=True)
def _sub_arc_open(b1x, b1y, b1z, b2x, b2y, b2z, hb, seg_arc, i, g, rho_lo, rho_hi, lo, hi):
    """:func:`kinematics.blocks._segment_open`, compiled once by numba and inlined by LLVM, not
    typed again at each call site (module docstring, *Compile time*)."""
    return _segment_open(b1x, b1y, b1z, b2x, b2y, b2z, hb, seg_arc, i, g, rho_lo, rho_hi, lo, hi)


@njit(cache=True, nogil=True, forceinline=True)
def _feasible_call(b1x, b1y, b1z, b2x, b2y, b2z, c, s, hb, rho_lo, rho_hi, lo2, hi2):
    """:func:`kinematics.feasibility.feasible_plain` for the child's rarer tests, compiled once by numba
    and inlined by LLVM (module docstring, *Compile time*)."""
    return feasible_plain(b1x, b1y, b1z, b2x, b2y, b2z, c, s, hb, rho_lo, rho_hi, lo2, hi2)


@njit(cache=True, inline="always")
def _visited(k, seg_k, seg_state, narrow, b1x, b1y, b1z, b2x, b2y, b2z, hb, seg_arc, i, rho_lo, rho_hi, lo_b, hi_b):
    """Whether :func:`kinematics.blocks.decide_chain` visits sample ``k`` of the window: always when
    ``narrow``, else when a sub-arc holding it is open (its bound computed once, cached in
    ``seg_state``: 0 not yet, 1 open, 2 rejected)."""
    if narrow:
        return True
    n_seg = seg_k.shape[0]
    per = seg_k[0, 1] - seg_k[0, 0]
    g1 = min(k // per, n_seg - 1) if per > 0 else 0
    for g in range(max(g1 - 1, 0), min(g1 + 1, n_seg - 1) + 1):
        if seg_k[g, 0] <= k <= seg_k[g, 1]:
            if seg_state[g] == 0:
                seg_state[g] = 1 if _sub_arc_open(b1x, b1y, b1z, b2x, b2y, b2z, hb, seg_arc, i, g, rho_lo, rho_hi,
                                                  lo_b, hi_b) else 2
            if seg_state[g] == 1:
                return True
    return False


@njit(cache=True, inline="always")
def _child_chain(px, py, pz, u, i, cos_t, sin_t, arc, seg_k, seg_arc, hb, rho_lo, rho_hi, lmin, lmax,
                 e_bound, e_relax, e_tight, can_ok, kwin, c, flags, lists, counts, seg_state, need_window):
    """:func:`kinematics.blocks.decide_chain`'s decision for one child, visiting only the samples
    its parent's ``flags`` leave open (module docstring); its window too when
    ``need_window``. A sample that passes the tight test lies in an open sub-arc (the sub-arc bounds
    reject only poses at least ``2 delta`` outside the tight limits), so the tight tests come first,
    and the bounds are computed only for the sub-arcs of samples that pass the relaxed test.
    Without joint cones: each test is :func:`kinematics.feasibility.feasible_plain`, which answers as
    :func:`kinematics.feasibility._feasible_at` there.

    The samples are visited from the parent's lists (:func:`_sample_lists`: ``lists[0]`` those with
    ``X``, ``lists[1]`` with ``R0``, ``lists[2]`` with ``R1`` but not ``R0``, ascending;
    ``counts``: their lengths), in the order a scan of the window visits them: the same tests in
    the same order as a scan that skips the samples without the flag."""
    b1x, b1y, b1z, b2x, b2y, b2z = chain_points(px, py, pz, u, i)
    n = cos_t.shape[1]
    klo = max(kwin[c, i, 1], 0)
    khi = min(kwin[c, i, 2], n - 1)
    hint = kwin[c, i, 0]
    if hint < klo or hint > khi:
        hint = (klo + khi) // 2
    lo_r = max(lmin - e_relax, 0.0)
    hi_r = lmax + e_relax
    lo_r2, hi_r2 = lo_r * lo_r, hi_r * hi_r
    lo_t = lmin + e_tight
    hi_t = lmax - e_tight
    can_ok = can_ok and lo_t <= hi_t
    lo_t2, hi_t2 = lo_t * lo_t, hi_t * hi_t
    if klo > khi:
        return FAIL
    n_x, n_r0, n_r1 = counts[i, 0], counts[i, 1], counts[i, 2]
    if n_r0 + n_r1 == 0:  # no sample can pass the relaxed test (R0 and X imply R1), nor the tight one
        return FAIL
    if can_ok:
        if flags[i, hint] & _X and _feasible_call(b1x, b1y, b1z, b2x, b2y, b2z, cos_t[i, hint],
                                                  sin_t[i, hint], hb, rho_lo, rho_hi, lo_t2, hi_t2):
            kwin[c, i, 0] = hint
            return OK
        for t in range(n_x):
            k = lists[i, 0, t]
            if k == hint:
                continue
            # both tests must pass (as in decide_chain): the tight one first, it fails more often
            if feasible_plain(b1x, b1y, b1z, b2x, b2y, b2z, cos_t[i, k], sin_t[i, k], hb, rho_lo, rho_hi, lo_t2,
                              hi_t2):
                if flags[i, k] & _R0 or _feasible_call(b1x, b1y, b1z, b2x, b2y, b2z, cos_t[i, k], sin_t[i, k],
                                                       hb, rho_lo, rho_hi, lo_r2, hi_r2):
                    kwin[c, i, 0] = k
                    return OK
    lo_b = max(lmin - e_bound, 0.0)
    hi_b = lmax + e_bound
    narrow = khi - klo < seg_k[0, 1] - seg_k[0, 0]
    if not narrow and not _stroke_open(b1x, b1y, b1z, b2x, b2y, b2z, hb, arc, i, rho_lo, rho_hi, lo_b, hi_b):
        return FAIL
    for g in range(seg_k.shape[0]):
        seg_state[g] = 0
    # visited samples with R0 pass the relaxed test untested: the lowest and highest of them first
    r0_lo = -1
    for t in range(n_r0):
        k = lists[i, 1, t]
        if _visited(k, seg_k, seg_state, narrow, b1x, b1y, b1z, b2x, b2y, b2z, hb, seg_arc, i, rho_lo, rho_hi,
                    lo_b, hi_b):
            r0_lo = k
            break
    if r0_lo >= 0 and (not can_ok or not need_window):
        kwin[c, i, 0] = r0_lo
        return UNKNOWN
    # the first visited sample (from below) that passes the relaxed test: only below r0_lo
    p_lo = r0_lo
    for t in range(n_r1):
        k = lists[i, 2, t]
        if r0_lo >= 0 and k >= r0_lo:
            break
        if feasible_plain(b1x, b1y, b1z, b2x, b2y, b2z, cos_t[i, k], sin_t[i, k], hb, rho_lo, rho_hi, lo_r2, hi_r2):
            if _visited(k, seg_k, seg_state, narrow, b1x, b1y, b1z, b2x, b2y, b2z, hb, seg_arc, i, rho_lo, rho_hi,
                        lo_b, hi_b):
                p_lo = k
                break
    if p_lo < 0:
        return FAIL
    if not can_ok:
        kwin[c, i, 0] = p_lo
        return UNKNOWN
    if not need_window:
        return UNKNOWN
    r0_hi = -1
    for t in range(n_r0 - 1, -1, -1):
        k = lists[i, 1, t]
        if k <= p_lo:
            break
        if _visited(k, seg_k, seg_state, narrow, b1x, b1y, b1z, b2x, b2y, b2z, hb, seg_arc, i, rho_lo, rho_hi,
                    lo_b, hi_b):
            r0_hi = k
            break
    p_hi = max(p_lo, r0_hi)
    for t in range(n_r1 - 1, -1, -1):
        k = lists[i, 2, t]
        if k <= p_hi:
            break
        if _feasible_call(b1x, b1y, b1z, b2x, b2y, b2z, cos_t[i, k], sin_t[i, k], hb, rho_lo, rho_hi, lo_r2, hi_r2):
            if _visited(k, seg_k, seg_state, narrow, b1x, b1y, b1z, b2x, b2y, b2z, hb, seg_arc, i, rho_lo, rho_hi,
                        lo_b, hi_b):
                p_hi = k
                break
    kwin[c, i, 0] = min(max(hint, p_lo), p_hi)
    kwin[c, i, 1] = p_lo
    kwin[c, i, 2] = p_hi
    return UNKNOWN


@njit(cache=True, inline="always")
def _sample_lists(flags, i, klo, khi, lists, counts):
    """The samples ``klo..khi`` by their flags (:func:`_child_chain`): ``lists[0]`` those with ``X``,
    ``lists[1]`` with ``R0``, ``lists[2]`` with ``R1`` but not ``R0``, ascending."""
    n_x = n_r0 = n_r1 = 0
    for k in range(klo, khi + 1):
        f = flags[i, k]
        if f & _X:
            lists[i, 0, n_x] = k
            n_x += 1
        if f & _R0:
            lists[i, 1, n_r0] = k
            n_r0 += 1
        elif f & _R1:
            lists[i, 2, n_r1] = k
            n_r1 += 1
    counts[i, 0] = n_x
    counts[i, 1] = n_r0
    counts[i, 2] = n_r1


@njit(parallel=True, cache=True, nogil=True)
def children_kernel(parents, pbits, pwin, size, eps, arc_slack, zfloor,
                    u, cos_t, sin_t, arc, seg_k, seg_arc, hb, rho_lo, rho_hi, lmin, lmax, offsets, need_window,
                    out, kbits, kwin, centres):
    """INSIDE / OUTSIDE / BOUNDARY of the 8 children (edge ``size``, centres ``parent + size *
    offsets[j]``, or ``centres[8 p + j]`` where ``centres`` is not empty: the same points as given by a
    grid's axes) of each parent cube (``parents`` (N, 3)): child ``8 p + j`` in ``out``, its chains
    proven inside in ``kbits`` (the parent's ``pbits`` and those it proves) and, where
    ``need_window``, its windows in ``kwin`` (from the parent's ``pwin``, updated) -- as
    :func:`kinematics.bracket._subcube_kernel` on the same children, with the parent's sample flags
    (module docstring). Without joint cones only (:func:`has_cones`). Without ``need_window`` (the
    last level, the grid's cubes) ``kwin`` is not touched and may be empty: the children's windows
    live in scratch (72 bytes a child, 137 MB over the 1.9 M children of the default bracket's
    second level at h = 2, written for nothing before)."""
    delta = 0.5 * size * math.sqrt(3.0)
    e_relax = delta + arc_slack + eps
    e_tight = delta + eps
    s = 0.5 * eps
    r1 = e_relax + delta + s
    r0 = e_relax - delta - s
    x = e_tight - delta - s
    n = cos_t.shape[1]
    m = parents.shape[0]
    for chunk in prange((m + _CHUNK - 1) // _CHUNK):
        # one set of scratch per run of parents, not one per parent (about 9 % of the kernel's time)
        flags = np.empty((3, n), np.uint8)
        lists = np.empty((3, 3, n), np.int64)
        counts = np.empty((3, 3), np.int64)
        done = np.empty(3, np.bool_)
        seg_state = np.zeros(seg_k.shape[0], np.int8)
        kw = np.empty((8, 3, 3), np.int64)  # the windows of the parent's children
        for p in range(chunk * _CHUNK, min(m, (chunk + 1) * _CHUNK)):
            counts[:] = 0
            done[:] = False
            for j in range(8):
                c = 8 * p + j
                if centres.shape[0] > 0:
                    px, py, pz = centres[c, 0], centres[c, 1], centres[c, 2]
                else:
                    px = parents[p, 0] + size * offsets[j, 0]
                    py = parents[p, 1] + size * offsets[j, 1]
                    pz = parents[p, 2] + size * offsets[j, 2]
                below = pz - 0.5 * size < zfloor - eps
                kbits[c] = pbits[p]
                for i in range(3):
                    for t in range(3):
                        kw[j, i, t] = pwin[p, i, t]
                cls = INSIDE
                for i in range(3):
                    if (kbits[c] >> i) & 1:
                        continue
                    if not done[i]:
                        klo = max(pwin[p, i, 1], 0)
                        khi = min(pwin[p, i, 2], n - 1)
                        if klo <= khi:
                            _parent_flags(parents[p, 0], parents[p, 1], parents[p, 2], u, i, cos_t, sin_t, seg_k,
                                          seg_arc, hb, rho_lo, rho_hi, lmin, lmax, klo, khi, r1, r0, x, flags)
                            _sample_lists(flags, i, klo, khi, lists, counts)
                        done[i] = True
                    st = _child_chain(px, py, pz, u, i, cos_t, sin_t, arc, seg_k, seg_arc, hb, rho_lo, rho_hi, lmin,
                                      lmax, delta + eps, e_relax, e_tight, not below, kw, j, flags, lists,
                                      counts, seg_state, need_window)
                    if st == FAIL:
                        cls = OUTSIDE
                        break
                    if st == UNKNOWN:
                        cls = BOUNDARY
                    else:
                        kbits[c] |= 1 << i
                out[c] = cls
                if need_window:
                    for i in range(3):
                        for t in range(3):
                            kwin[c, i, t] = kw[j, i, t]
