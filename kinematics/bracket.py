"""A certified bracket of the continuous workspace volume: ``volume_inner <= V <= volume_outer``.

The voxel count ``N h^3`` estimates the volume ``V`` of the continuous workspace ``W`` (every
platform position, at the fixed orientation, for which every chain has SOME carriage pose with the
arc angle anywhere in the stroke, not only at the samples). Here each voxel is a closed **cube**
of edge ``h`` (not its centre), classified with the coarse-to-fine machinery of
:mod:`kinematics.blocks` as certainly inside ``W``, certainly outside, or boundary:

Notation: a block of cubes is a box with centre ``Pc`` and half-diagonal ``delta`` (every point
of every cube of the block is within ``delta`` of ``Pc``); the arc samples are ``Delta_eta``
apart (both stroke ends are samples, so every arc angle is within ``Delta_eta / 2`` of one);
``R_D = sqrt(r^2 + (b/2)^2)`` bounds the distance of a U joint from the base axis (``rho <= r``);
``eps`` is a rounding margin (1e-9 of the design's scale).

* **inside** (for chain ``i``): some arc sample admits a ``rho`` with both legs in
  ``[l_min + delta + eps, l_max - delta - eps]`` at ``Pc``. By the Lipschitz lemma of
  :mod:`kinematics.blocks` the same ``(sample, rho)`` works for every point of the block.
* **outside**: the whole-stroke bound with limits relaxed by ``delta`` rejects ``Pc``, or no
  sample admits a ``rho`` with legs in ``[l_min - e, l_max + e]``, ``e = delta + R_D Delta_eta/2
  + eps``. Proof: if a point ``P`` of the block were served by ``(eta, rho)`` with exact limits,
  take the nearest sample ``eta_k``; the U joints move by at most ``R_D |eta - eta_k| <= R_D
  Delta_eta / 2`` (a rotation about the base axis), and ``|P - Pc| <= delta``, so every leg length
  at ``(Pc, eta_k, rho)`` is within ``e`` of the one at ``(P, eta, rho)``: sample ``k`` would pass
  the relaxed test. (The whole-stroke bound is conservative over the continuous stroke, so its
  relaxation by ``delta`` alone is enough.)
* **outside, per sub-arc**: the whole-stroke bound is conservative over any continuous part of the
  stroke, so it also rejects a sub-arc between two samples (relaxed by ``delta`` alone): the samples
  of a rejected sub-arc need no test, and a cube is outside when every sub-arc is rejected or every
  sample of the others fails the relaxed test above.
* a block is split while undecided; a single cube left undecided is a **boundary** cube (the 8 cubes
  of an undecided block of 2 x 2 x 2 are decided together, by the refinement's per-parent step on
  their own centres: :func:`_cubes_by_parent`; the same decisions as one by one).

A cube is inside ``W`` when all three chains are inside, outside when one chain is outside.
Then ``N_in h^3 <= V <= (N_in + N_boundary) h^3`` for the part of ``W`` in the grid box (the
derived grid box contains all of ``W``: see :func:`kinematics.workspace.default_bounds`); cubes
reaching below ``z_floor`` are never counted inside. The voxel estimate lies in the bracket by
construction (an inside cube has a reachable centre; a reachable centre's cube is not outside),
and the gap ``N_boundary h^3`` shrinks about linearly with ``h`` (the boundary cubes form a
shell of about one cube's thickness).

**Refinement** (``refine`` levels, default :data:`REFINE`): every boundary cube is split into 8
children of half the edge, each classified by the same two tests (its own centre and
half-diagonal); inside children add their volume to the inner bound, outside children remove theirs
from the outer bound, boundary children are split again. Each level is as rigorous as the first
and divides the gap by about two, at the cost of testing the boundary shell only. So that the arc
slack ``R_D Delta_eta / 2`` does not stall the refinement, each level tests the arc at ``fine``
samples per gap of the workspace's samples (all of which are kept), the fewest that make the slack at
most half the cubes' half-diagonal (:func:`_arc`, at most :data:`MAX_FINE`): both tests stay as
rigorous (any arc angle is a valid carriage pose for the inside test; the slack shrinks with the
spacing for the outside test).

**Mirror.** With the centered arc range and zero orientation the mechanism, hence ``W``, is symmetric
under ``y -> -y`` (chain 1 onto itself, chains 2 and 3 swapped). A cube inside (outside) ``W`` then has
its mirror image inside (outside) ``W``: on a grid whose y centres are exactly symmetric, so that the
image of a cube is a cube of the grid, only the cubes with ``y <= 0`` are classified and the others
take their image's class (and its chains, 2 and 3 swapped); the refinement splits the boundary cubes
of that half and counts the children of a cube off the middle row twice, in about half the time. The
bracket is as rigorous as with every cube classified; it differs from it only where a block is
decided as a whole in one and cube by cube in the other (their top blocks are laid out differently):
the default design at h = 2, refine 2, has the same inner bound and an outer one 0.5 units^3 lower.
"""

from __future__ import annotations

import dataclasses
import math
from typing import Any

import numpy as np
from numba import njit, prange

from .blocks import (
    FAIL,
    LEVELS,
    OK,
    TOP_BLOCK,
    UNKNOWN,
    _advance,
    _top_blocks,
    block_centre,
    decide_chain,
    initial_windows,
    rounding_margin,
    sub_arcs,
)
from .bracket_children import children_kernel, has_cones
from .design import Design, ParameterError
from .feasibility import ChainTables
from .grid import GridSpec
from .kernel_args import KernelArgs, kernel_args
from .parallel import KERNEL_LOCK, kernel_launch
from .progress import CancelToken, Reporter, check

__all__ = ["VolumeBracket", "volume_bracket", "bracket_of"]

INSIDE, OUTSIDE, BOUNDARY = 1, 2, 0
#: Written by :func:`kinematics.blocks._advance` beside a cube's chain bits where a chain fails.
_FAILED = 8
#: Halvings of the boundary cubes by default (each one divides the bracket's gap by about 2).
REFINE = 2
#: How :func:`refine_boundary` decides a boundary cube's children (its ``method``).
METHODS = ("parents", "cubes")
#: Most arc samples per gap of the workspace's samples in the outside test (:func:`_arc`).
MAX_FINE = 16
#: Why there is no bracket with leg interference (the refusal of ``bracket`` and the explorer's words).
NO_BRACKET_INTERFERENCE = "not available with leg interference (leg_diameter > 0)"


@dataclasses.dataclass(frozen=True)
class VolumeBracket:
    """``volume_inner <= V <= volume_outer`` for the continuous workspace (units^3)."""

    volume_inner: float
    volume_outer: float
    cubes_inside: int
    cubes_boundary: int
    voxel: float
    refine: int = 0
    boundary_left: int = 0

    @property
    def gap(self) -> float:
        """``volume_outer - volume_inner``."""
        return self.volume_outer - self.volume_inner

    def to_dict(self) -> dict:
        """JSON form (``volume_inner``, ``volume_outer``, counts, gap)."""
        return {**dataclasses.asdict(self), "gap": self.gap}


@njit(cache=True, forceinline=True)
def _cube_chain(px, py, pz, delta, arc_slack, cone_slack, below, eps, i, win,
                u, cos_t, sin_t, arc, seg_k, seg_arc, hb, rho_lo, rho_hi, lmin, lmax, jc):
    """OK (inside), FAIL (outside) or UNKNOWN for chain ``i`` over the cube (or block) of centre
    ``P`` and half-diagonal ``delta`` (module docstring), with the arc samples of ``cos_t, sin_t``
    (``arc_slack``/``cone_slack``: the joint motion over their half-spacing) in the window ``win``
    of :func:`kinematics.blocks.decide_chain` (a sample that failed the parent's outside test, with
    its slack, holds no angle that serves any point of the parent, hence of this cube)."""
    return decide_chain(px, py, pz, u, i, cos_t, sin_t, arc, seg_k, seg_arc, hb, rho_lo, rho_hi, lmin, lmax, jc,
                        delta + eps, delta + arc_slack + eps, delta + cone_slack + eps, delta + eps, not below,
                        win)


@njit(parallel=True, cache=True, nogil=True)
def _cube_kernel(b0, bn, state, win, xs, ys, zs, h, eps, arc_slack, cone_slack, zfloor,
                 u, cos_t, sin_t, arc, seg_k, seg_arc, hb, rho_lo, rho_hi, lmin, lmax, jc):
    for b in prange(b0.shape[0]):
        nx, ny, nz = bn[b, 0], bn[b, 1], bn[b, 2]
        px, py, pz = block_centre(b0, bn, b, xs, ys, zs)
        delta = 0.5 * h * math.sqrt(nx * nx + ny * ny + nz * nz)
        below = zs[b0[b, 2]] - 0.5 * h < zfloor - eps
        for i in range(3):
            if state[b, i] != UNKNOWN:
                continue
            st = _cube_chain(px, py, pz, delta, arc_slack, cone_slack, below, eps, i, win[b, i],
                             u, cos_t, sin_t, arc, seg_k, seg_arc, hb, rho_lo, rho_hi, lmin, lmax, jc)
            state[b, i] = st
            if st == FAIL:
                break


@njit(parallel=True, cache=True, nogil=True)
def _subcube_kernel(centres, bits, win, size, eps, arc_slack, cone_slack, zfloor,
                    u, cos_t, sin_t, arc, seg_k, seg_arc, hb, rho_lo, rho_hi, lmin, lmax, jc, out):
    """INSIDE / OUTSIDE / BOUNDARY of cubes of edge ``size`` centred at ``centres`` (N, 3); bit ``i``
    of ``bits`` marks chain ``i`` as already inside (inherited from the parent cube; updated);
    ``win`` (N, 3, 3): each chain's sample window (updated)."""
    delta = 0.5 * size * math.sqrt(3.0)
    for c in prange(centres.shape[0]):
        px, py, pz = centres[c, 0], centres[c, 1], centres[c, 2]
        below = pz - 0.5 * size < zfloor - eps
        cls = INSIDE
        for i in range(3):
            if (bits[c] >> i) & 1:
                continue
            st = _cube_chain(px, py, pz, delta, arc_slack, cone_slack, below, eps, i, win[c, i],
                             u, cos_t, sin_t, arc, seg_k, seg_arc, hb, rho_lo, rho_hi, lmin, lmax, jc)
            if st == FAIL:
                cls = OUTSIDE
                break
            if st == UNKNOWN:
                cls = BOUNDARY
            else:
                bits[c] |= 1 << i
        out[c] = cls


def _slacks(design: Design, grid: GridSpec, lmax: float, n_eta: int) -> tuple[float, float, float]:
    """``(arc_slack, cone_slack, eps)`` of the outside test with ``n_eta`` arc samples (module docstring)."""
    lo, hi = design.eta_limits
    d_eta = math.radians(hi - lo) / (n_eta - 1) if n_eta > 1 else 0.0
    arc_slack = math.hypot(design.r, 0.5 * design.b) * 0.5 * d_eta
    xs, ys, zs = grid.axes()
    # joint cones: between arc samples the U joint moves by <= R_D d_eta/2 (base frame) and, in the
    # carriage's frame, the S joint by <= |B_xy| d_eta/2 with |B_xy| <= max |P_xy| + |u_xy|
    rb = math.hypot(max(abs(xs[0]), abs(xs[-1])) + grid.h, max(abs(ys[0]), abs(ys[-1])) + grid.h) + design.a
    cone_slack = max(math.hypot(design.r, 0.5 * design.b), rb) * 0.5 * d_eta
    return arc_slack, cone_slack, rounding_margin(lmax, (xs, ys, zs))


@dataclasses.dataclass(frozen=True)
class _Arc:
    """The arc samples one level of the bracket tests with (``fine`` per gap of the workspace's
    samples, so the arc slack is ``fine`` times smaller), their sub-arcs and slacks."""

    cos_t: np.ndarray
    sin_t: np.ndarray
    seg_k: np.ndarray
    seg_arc: np.ndarray
    arc_slack: float
    cone_slack: float
    eps: float
    fine: int


def _arc(design: Design, grid: GridSpec, args: KernelArgs, n_eta: int, delta: float) -> _Arc:
    """Arc samples fine enough that their slack is at most half the cubes' half-diagonal ``delta``:
    ``fine`` samples per gap of the workspace's samples (which are all kept), a power of two up to
    :data:`MAX_FINE`."""
    lmax = math.sqrt(args[8])
    arc_slack, _, _ = _slacks(design, grid, lmax, n_eta)
    need = 2.0 * arc_slack / delta
    fine = 1  # a power of two, so that one level's samples contain the previous level's
    while n_eta > 1 and fine < need - 1e-9 and fine < MAX_FINE:
        fine *= 2
    n_f = (n_eta - 1) * fine + 1 if n_eta > 1 else 1
    cos_t, sin_t = args[1], args[2]
    if fine > 1:
        tab = ChainTables(design, n_f)
        cos_t, sin_t = tab.cos_t, tab.sin_t
    seg_k, seg_arc = sub_arcs(cos_t, sin_t, 6 * fine)
    a_s, c_s, eps = _slacks(design, grid, lmax, n_f)
    return _Arc(cos_t, sin_t, seg_k, seg_arc, a_s, c_s, eps, fine)


def _rescale_windows(win: np.ndarray, r: int, n: int) -> np.ndarray:
    """Windows of :func:`kinematics.blocks.decide_chain` in samples ``r`` times finer (``n`` of
    them): sample ``k`` becomes ``r k``, and a window keeps every new sample whose nearest old sample
    was in it (the old outside test covered the angles within half an old spacing of a sample)."""
    if r == 1:
        return win
    out = np.empty_like(win)
    with kernel_launch(win.shape[0]):
        _rescale_kernel(win, r, n, out)
    return out


@njit(parallel=True, cache=True, nogil=True)
def _rescale_kernel(win, r, n, out):
    """:func:`_rescale_windows` of every block's three windows into ``out``."""
    for b in prange(win.shape[0]):
        for i in range(3):
            out[b, i, 0] = win[b, i, 0] * r
            out[b, i, 1] = max(win[b, i, 1] * r - r // 2, 0)
            out[b, i, 2] = min(win[b, i, 2] * r + r // 2, n - 1)


def _half(grid: GridSpec, symmetric: bool) -> bool:
    """Whether only the cubes with ``y <= 0`` are classified (module docstring, *Mirror*): the workspace
    is symmetric and the grid's y centres are exactly so (else every cube is)."""
    return symmetric and grid.is_mirror_symmetric_y(exact=True)


@njit(parallel=True, cache=True, nogil=True)
def _finish_classes(v, m, out, bits):
    """``out``: INSIDE / OUTSIDE / BOUNDARY of every cube from ``v`` (the chains proven inside, |
    ``_FAILED`` where one fails), ``bits``: its chains proven inside; the rows ``y >= ny - m`` take
    those of their mirror image ``ny - 1 - y`` (*Mirror*; ``m = 0``: no mirror), with the bits of
    chains 2 and 3 swapped (the mirror maps chain 2 onto chain 3)."""
    nx, ny, nz = v.shape
    for x in prange(nx):
        for y in range(ny):
            src = ny - 1 - y if y >= ny - m else y
            for z in range(nz):
                c = v[x, src, z]
                b = c & 7
                if src != y:
                    b = (b & 1) | ((b & 2) << 1) | ((b & 4) >> 1)
                bits[x, y, z] = b
                out[x, y, z] = OUTSIDE if c & _FAILED else (INSIDE if b == 7 else BOUNDARY)


@njit(parallel=True, cache=True, nogil=True)
def _boundary_cubes(cls, y_end):
    """``(x, y, z)`` of every BOUNDARY cube with ``y < y_end``, in C order (as ``np.argwhere``)."""
    nx, ny, nz = cls.shape
    per_x = np.zeros(nx + 1, np.int64)
    for x in prange(nx):
        c = 0
        for y in range(y_end):
            for z in range(nz):
                c += cls[x, y, z] == BOUNDARY
        per_x[x + 1] = c
    for x in range(nx):
        per_x[x + 1] += per_x[x]
    idx = np.empty((per_x[nx], 3), np.int64)
    for x in prange(nx):
        c = per_x[x]
        for y in range(y_end):
            for z in range(nz):
                if cls[x, y, z] == BOUNDARY:
                    idx[c, 0] = x
                    idx[c, 1] = y
                    idx[c, 2] = z
                    c += 1
    return idx


@njit(cache=True, nogil=True)
def _tally(out, weight):
    """Weighted counts ``(inside, outside, boundary)`` of the children ``out`` (child ``8 p + j`` of
    parent ``p`` weighs ``weight[p]``)."""
    t = np.zeros(3)
    for c in range(out.shape[0]):
        t[out[c]] += weight[c // 8]
    return t


@njit(cache=True, nogil=True)
def _keep_boundary(out, parents, bits, win, weight, size, offsets, at, c_out, b_out, w_out, wt_out):
    """Append the BOUNDARY children of ``out`` (child ``8 p + j``: centre ``parents[p] + size *
    offsets[j]``, its chain bits, windows and its parent's weight) at row ``at`` of the ``*_out``
    arrays; returns the new row count."""
    for c in range(out.shape[0]):
        if out[c] != BOUNDARY:
            continue
        p, j = c // 8, c % 8
        for t in range(3):
            c_out[at, t] = parents[p, t] + size * offsets[j, t]
        b_out[at] = bits[c]
        for i in range(3):
            for t in range(3):
                w_out[at, i, t] = win[c, i, t]
        wt_out[at] = weight[p]
        at += 1
    return at


#: The eight child-cube offsets (in units of the child's edge) from a cube's centre.
_CHILDREN = np.array([[dx, dy, dz] for dx in (-0.5, 0.5) for dy in (-0.5, 0.5) for dz in (-0.5, 0.5)])
#: :func:`kinematics.bracket_children.children_kernel`'s ``centres`` when the children are parent + offset.
_NO_CENTRES = np.zeros((0, 3))
#: Its ``kwin`` where the children's windows are not needed (``need_window`` False).
_NO_WINDOWS = np.zeros((0, 3, 3), np.int64)
#: Parents per launch of :func:`kinematics.bracket_children.children_kernel`.
_PARENTS_PER_CALL = 1 << 15


def _cubes_by_parent(b0: np.ndarray, bn: np.ndarray, state: np.ndarray, win: np.ndarray, axes: tuple,
                     h: float, fa: _Arc, z_floor: float, args: KernelArgs, v: np.ndarray,
                     cancel: CancelToken) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Decide the 8 cubes of every undecided block of 2 x 2 x 2 cubes together (the refinement's
    per-parent step, :mod:`kinematics.bracket_children`, on the grid's own centres), writing their
    chains proven inside, ``| _FAILED`` where one fails, into ``v``; return the other blocks. Each
    cube gets the decision (and chain bits) that :func:`_cube_kernel` gives it as a single cube after
    :func:`kinematics.blocks._advance` splits its block: the same centre, half-diagonal, window and
    inherited chains (``_subcube_kernel``'s test, which the per-parent step reproduces)."""
    u, _, _, arc, hb, rho_lo, rho_hi, lmin2, lmax2, _ = args
    sel = (np.all(bn == 2, axis=1) & ~np.any(state == FAIL, axis=1) & np.any(state == UNKNOWN, axis=1))
    if not sel.any():
        return b0, bn, state, win
    xs, ys, zs = axes
    pb0 = b0[sel]
    pbits = ((state[sel] == OK) * np.array([1, 2, 4])).sum(axis=1).astype(np.uint8)
    pwin = np.ascontiguousarray(win[sel])
    parents = np.stack([0.5 * (xs[pb0[:, 0]] + xs[pb0[:, 0] + 1]), 0.5 * (ys[pb0[:, 1]] + ys[pb0[:, 1] + 1]),
                        0.5 * (zs[pb0[:, 2]] + zs[pb0[:, 2] + 1])], axis=1)
    step = (_CHILDREN > 0).astype(np.int64)  # child j's cube: the block's lower corner + step[j]
    for s in range(0, parents.shape[0], _PARENTS_PER_CALL):
        check(cancel)
        e = min(s + _PARENTS_PER_CALL, parents.shape[0])
        gx, gy, gz = ((pb0[s:e, None, a] + step[None, :, a]).ravel() for a in range(3))
        centres = np.ascontiguousarray(np.stack([xs[gx], ys[gy], zs[gz]], axis=1))
        n_kids = 8 * (e - s)
        out = np.empty(n_kids, np.uint8)
        kbits = np.empty(n_kids, np.uint8)
        with kernel_launch(e - s):
            children_kernel(np.ascontiguousarray(parents[s:e]), np.ascontiguousarray(pbits[s:e]), pwin[s:e], float(h),
                            fa.eps, fa.arc_slack, float(z_floor), u, fa.cos_t, fa.sin_t, arc, fa.seg_k, fa.seg_arc,
                            hb, rho_lo, rho_hi, math.sqrt(lmin2), math.sqrt(lmax2), _CHILDREN, False, out, kbits,
                            _NO_WINDOWS, centres)
        v[gx, gy, gz] = kbits | np.where(out == OUTSIDE, _FAILED, 0).astype(np.uint8)
    keep = ~sel
    return b0[keep], bn[keep], state[keep], win[keep]


def cube_classes(design: Design, grid: GridSpec, args: KernelArgs, n_eta: int, z_floor: float,
                 progress: Reporter | None = None, cancel: CancelToken = None,
                 chain_bits: np.ndarray | None = None, symmetric: bool = False,
                 per_parent: bool = True) -> np.ndarray:
    """INSIDE / OUTSIDE / BOUNDARY for every cube of ``grid`` (uint8 array of the grid's shape);
    ``chain_bits`` (uint8, the grid's shape), when given, receives the chains proven inside per cube.
    ``symmetric``: the workspace is symmetric under ``y -> -y`` (module docstring, *Mirror*).
    ``per_parent`` (default; without joint cones): the 8 cubes of an undecided block of 2 x 2 x 2 are
    decided together (:func:`_cubes_by_parent`); ``False``: each on its own. The same classes and
    chain bits (tested)."""
    u, _, _, arc, hb, rho_lo, rho_hi, lmin2, lmax2, jc = args
    lmin, lmax = math.sqrt(lmin2), math.sqrt(lmax2)
    fa = _arc(design, grid, args, n_eta, 0.5 * grid.h * math.sqrt(3.0))
    xs, ys, zs = (np.ascontiguousarray(a, dtype=np.float64) for a in grid.axes())
    v = np.zeros(grid.shape, np.uint8)  # per cube: the chains proven inside, | _FAILED where one fails
    by_parent = per_parent and not has_cones(jc)
    half = _half(grid, symmetric)
    nx, ny, nz = grid.shape
    b0, bn = _top_blocks((nx, ny - ny // 2 if half else ny, nz), TOP_BLOCK)
    state = np.zeros((b0.shape[0], 3), np.int8)
    win = initial_windows(b0.shape[0], fa.cos_t.shape[1])
    level = 0
    while b0.shape[0]:
        check(cancel)
        for s in range(0, b0.shape[0], 65536):
            check(cancel)
            with KERNEL_LOCK:
                _cube_kernel(b0[s:s + 65536], bn[s:s + 65536], state[s:s + 65536], win[s:s + 65536], xs, ys, zs,
                             float(grid.h), fa.eps, fa.arc_slack, fa.cone_slack, float(z_floor), u, fa.cos_t,
                             fa.sin_t, arc, fa.seg_k, fa.seg_arc, hb, rho_lo, rho_hi, lmin, lmax, jc)
        if by_parent:
            b0, bn, state, win = _cubes_by_parent(b0, bn, state, win, (xs, ys, zs), grid.h, fa, z_floor, args, v,
                                                  cancel)
        with kernel_launch(b0.shape[0]):  # decided blocks and single cubes written, the others split
            b0, bn, state, win = _advance(b0, bn, state, win, False, v, _FAILED)
        level += 1
        if progress is not None:
            progress(min(0.5, level / 10.0),
                     f"certified bracket: classifying the cubes, level {level} (of at most {LEVELS})")
    out = np.empty(grid.shape, np.uint8)
    bits = np.empty(grid.shape, np.uint8) if chain_bits is None else chain_bits
    with kernel_launch(nx):
        _finish_classes(v, ny // 2 if half else 0, out, bits)
    return out


def refine_boundary(design: Design, grid: GridSpec, args: KernelArgs, n_eta: int, z_floor: float, cls: np.ndarray,
                    chain_bits: np.ndarray, levels: int, progress: Reporter | None = None,
                    cancel: CancelToken = None, method: str = "parents",
                    symmetric: bool = False) -> tuple[float, float, int]:
    """Split each boundary cube into 8 children ``levels`` times, classifying every child with the
    same tests as the cubes (module docstring): returns ``(inside volume found, outside volume found,
    boundary children left)``; the bracket becomes ``[V_in + inside, V_out - outside]``. A child
    inherits the chains its parent proved inside (``chain_bits``) and tests only the others.

    ``method``: ``"parents"`` (default) decides the 8 children of a cube together, after one pass
    over the cube's samples at its centre (:mod:`kinematics.bracket_children`; without joint cones);
    ``"cubes"`` tests each child on its own. Both give the same classes (tested). ``symmetric``: the
    workspace is symmetric under ``y -> -y``; with a grid exactly so, only the boundary cubes with
    ``y <= 0`` are refined, those with ``y < 0`` counted twice (module docstring, *Mirror*)."""
    if method not in METHODS:
        raise ParameterError("method", method, " or ".join(METHODS))
    u, _, _, arc, hb, rho_lo, rho_hi, lmin2, lmax2, jc = args
    per_parent = method == "parents" and not has_cones(jc)
    lmin, lmax = math.sqrt(lmin2), math.sqrt(lmax2)
    half = _half(grid, symmetric)
    m = cls.shape[1] // 2 if half else 0
    with kernel_launch(cls.shape[0]):
        idx = _boundary_cubes(cls, cls.shape[1] - m)
    weight = np.where(idx[:, 1] < m, 2.0, 1.0)  # cubes each one stands for: 2 for one and its mirror image
    centres = np.asarray(grid.origin, dtype=np.float64) + grid.h * idx
    parent_bits = chain_bits[idx[:, 0], idx[:, 1], idx[:, 2]]
    size = float(grid.h)
    inside = outside = 0.0
    chunk = 1 << 15  # parents per kernel call
    parent_win = initial_windows(centres.shape[0], n_eta)  # in the workspace's samples
    fine_before = 1
    for level in range(levels):
        size *= 0.5
        fa = _arc(design, grid, args, n_eta, 0.5 * size * math.sqrt(3.0))
        parent_win = _rescale_windows(parent_win, fa.fine // fine_before, fa.cos_t.shape[1])
        fine_before = fa.fine
        last = level == levels - 1  # the last level's boundary children are only counted
        n_par = centres.shape[0]
        if not last:  # the boundary children, parents of the next level
            left = np.empty((8 * n_par, 3))
            left_bits = np.empty(8 * n_par, np.uint8)
            left_win = np.empty((8 * n_par, 3, 3), np.int64)
            left_weight = np.empty(8 * n_par)
        n_kept = 0
        n_left = 0.0
        for s in range(0, n_par, chunk):
            check(cancel)
            par = np.ascontiguousarray(centres[s:s + chunk])
            p_bits = np.ascontiguousarray(parent_bits[s:s + chunk])
            p_win = np.ascontiguousarray(parent_win[s:s + chunk])
            n_kids = 8 * par.shape[0]
            out = np.empty(n_kids, np.uint8)
            if per_parent:
                bits = np.empty(n_kids, np.uint8)
                win = _NO_WINDOWS if last else np.empty((n_kids, 3, 3), np.int64)
                with kernel_launch(par.shape[0]):
                    children_kernel(par, p_bits, p_win, size, fa.eps, fa.arc_slack, float(z_floor), u, fa.cos_t,
                                    fa.sin_t, arc, fa.seg_k, fa.seg_arc, hb, rho_lo, rho_hi, lmin, lmax, _CHILDREN,
                                    not last, out, bits, win, _NO_CENTRES)
            else:
                kids = np.ascontiguousarray((par[:, None, :] + size * _CHILDREN[None]).reshape(-1, 3))
                bits = np.ascontiguousarray(np.repeat(p_bits, 8))
                win = np.ascontiguousarray(np.repeat(p_win, 8, axis=0))
                with KERNEL_LOCK:
                    _subcube_kernel(kids, bits, win, size, fa.eps, fa.arc_slack, fa.cone_slack, float(z_floor), u,
                                    fa.cos_t, fa.sin_t, arc, fa.seg_k, fa.seg_arc, hb, rho_lo, rho_hi, lmin, lmax, jc,
                                    out)
            p_weight = np.ascontiguousarray(weight[s:s + chunk])
            counts = _tally(out, p_weight)
            inside += float(counts[INSIDE]) * size ** 3
            outside += float(counts[OUTSIDE]) * size ** 3
            n_left += float(counts[BOUNDARY])
            if not last:
                n_kept = _keep_boundary(out, par, bits, win, p_weight, size, _CHILDREN, n_kept, left, left_bits,
                                        left_win, left_weight)
        if progress is not None:
            progress(0.5 + 0.5 * (level + 1) / levels,
                     f"certified bracket: refining the boundary, level {level + 1} of {levels}")
        if last:
            return inside, outside, round(n_left)
        centres, parent_bits = left[:n_kept], left_bits[:n_kept]
        parent_win, weight = left_win[:n_kept], left_weight[:n_kept]
    return inside, outside, round(float(weight.sum()))


def volume_bracket(design: Design, grid: GridSpec, args: KernelArgs, n_eta: int, z_floor: float = 0.0,
                   progress: Reporter | None = None, cancel: CancelToken = None,
                   refine: int = REFINE, method: str = "parents", symmetric: bool = False) -> VolumeBracket:
    """The certified bracket of the continuous workspace volume over ``grid`` (module docstring):
    cubes of the grid, then ``refine`` halvings of the boundary cubes (:func:`refine_boundary`, with
    its ``method``). ``symmetric``: the caller knows the workspace is symmetric under ``y -> -y``
    (:meth:`kinematics.workspace.WorkspaceSettings.mirror_symmetric`); on a grid exactly so, half the
    cubes are classified (*Mirror*; an equally certified bracket)."""
    bits = np.zeros(grid.shape, np.uint8)
    cls = cube_classes(design, grid, args, n_eta, z_floor, progress, cancel, chain_bits=bits, symmetric=symmetric)
    n_in = int(np.count_nonzero(cls == INSIDE))
    n_b = int(np.count_nonzero(cls == BOUNDARY))
    v = grid.voxel_volume
    add, cut, left = (refine_boundary(design, grid, args, n_eta, z_floor, cls, bits, refine, progress, cancel,
                                      method, symmetric)
                      if refine > 0 else (0.0, 0.0, n_b))
    return VolumeBracket(volume_inner=n_in * v + add, volume_outer=(n_in + n_b) * v - cut, cubes_inside=n_in,
                         cubes_boundary=n_b, voxel=grid.h, refine=refine, boundary_left=left)


def bracket_of(result: object, progress: Reporter | None = None, cancel: CancelToken = None,
               refine: int | None = None) -> VolumeBracket:
    """:func:`volume_bracket` on the grid, orientation, arc samples and joint cones of a computed
    ``kinematics.workspace.WorkspaceResult`` (``refine``: default the settings' ``bracket_refine``).

    Raises:
        ParameterError: with leg interference (the bracket does not model it).
    """
    r: Any = result
    if r.settings.joints.min_distance > 0.0:
        raise ParameterError("bracket", True, NO_BRACKET_INTERFERENCE)
    args = kernel_args(r.design, r.settings.orientation, r.n_eta, r.settings.joints)
    return volume_bracket(r.design, r.grid, args, r.n_eta, r.settings.z_floor, progress, cancel,
                          refine=r.settings.bracket_refine if refine is None else refine,
                          symmetric=r.settings.mirror_symmetric(r.design))
