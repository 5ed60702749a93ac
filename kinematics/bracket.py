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
* a block is split while undecided; a single cube left undecided is a **boundary** cube.

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
and divides the gap by about two, at the cost of testing the boundary shell only. The arc slack
``R_D Delta_eta / 2`` does not shrink with the cubes: it bounds what refinement can gain.
"""

from __future__ import annotations

import dataclasses
import math
from typing import Any, Optional

import numpy as np
from numba import njit, prange

from .blocks import FAIL, OK, TOP_BLOCK, UNKNOWN, _fill_kernel, _split, _top_blocks, block_centre, rounding_margin
from .design import Design, ParameterError
from .feasibility import _chain_excluded, _feasible_at, chain_points
from .grid import GridSpec
from .parallel import KERNEL_LOCK
from .progress import CancelToken, Reporter, check

__all__ = ["VolumeBracket", "volume_bracket", "bracket_of"]

INSIDE, OUTSIDE, BOUNDARY = 1, 2, 0
#: Halvings of the boundary cubes by default (each one divides the bracket's gap by about 2).
REFINE = 2


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


@njit(cache=True, inline="always")
def _cube_chain(px, py, pz, delta, arc_slack, cone_slack, below, eps, i,
                u, cos_t, sin_t, arc, hb, rho_lo, rho_hi, lmin, lmax, jc):
    """OK (inside), FAIL (outside) or UNKNOWN for chain ``i`` over the cube (or block) of centre
    ``P`` and half-diagonal ``delta`` (module docstring)."""
    n = cos_t.shape[1]
    b1x, b1y, b1z, b2x, b2y, b2z = chain_points(px, py, pz, u, i)
    e0 = delta + eps
    lo0 = max(lmin - e0, 0.0)
    hi0 = lmax + e0
    if _chain_excluded(b1x, b1y, b1z, b2x, b2y, b2z, hb, arc[i], rho_lo, rho_hi, lo0 * lo0, hi0 * hi0):
        return FAIL
    e_out = delta + arc_slack + eps
    lo_r = max(lmin - e_out, 0.0)
    hi_r = lmax + e_out
    lo_t = lmin + e0
    hi_t = lmax - e0
    can_in = lo_t <= hi_t and not below
    some = False
    for k in range(n):
        if _feasible_at(b1x, b1y, b1z, b2x, b2y, b2z, cos_t[i, k], sin_t[i, k], hb, rho_lo, rho_hi,
                        lo_r * lo_r, hi_r * hi_r, jc[i], delta + cone_slack + eps):
            some = True
            if not can_in:
                break
            if _feasible_at(b1x, b1y, b1z, b2x, b2y, b2z, cos_t[i, k], sin_t[i, k], hb, rho_lo, rho_hi,
                            lo_t * lo_t, hi_t * hi_t, jc[i], -e0):
                return OK
    return UNKNOWN if some else FAIL


@njit(parallel=True, cache=True, nogil=True)
def _cube_kernel(b0, bn, state, xs, ys, zs, h, eps, arc_slack, cone_slack, zfloor,
                 u, cos_t, sin_t, arc, hb, rho_lo, rho_hi, lmin, lmax, jc):
    for b in prange(b0.shape[0]):
        nx, ny, nz = bn[b, 0], bn[b, 1], bn[b, 2]
        px, py, pz = block_centre(b0, bn, b, xs, ys, zs)
        delta = 0.5 * h * math.sqrt(nx * nx + ny * ny + nz * nz)
        below = zs[b0[b, 2]] - 0.5 * h < zfloor - eps
        for i in range(3):
            if state[b, i] != UNKNOWN:
                continue
            st = _cube_chain(px, py, pz, delta, arc_slack, cone_slack, below, eps, i,
                             u, cos_t, sin_t, arc, hb, rho_lo, rho_hi, lmin, lmax, jc)
            state[b, i] = st
            if st == FAIL:
                break


@njit(parallel=True, cache=True, nogil=True)
def _subcube_kernel(centres, bits, size, eps, arc_slack, cone_slack, zfloor,
                    u, cos_t, sin_t, arc, hb, rho_lo, rho_hi, lmin, lmax, jc, out):
    """INSIDE / OUTSIDE / BOUNDARY of cubes of edge ``size`` centred at ``centres`` (N, 3); bit ``i``
    of ``bits`` marks chain ``i`` as already inside (inherited from the parent cube; updated)."""
    delta = 0.5 * size * math.sqrt(3.0)
    for c in prange(centres.shape[0]):
        px, py, pz = centres[c, 0], centres[c, 1], centres[c, 2]
        below = pz - 0.5 * size < zfloor - eps
        cls = INSIDE
        for i in range(3):
            if (bits[c] >> i) & 1:
                continue
            st = _cube_chain(px, py, pz, delta, arc_slack, cone_slack, below, eps, i,
                             u, cos_t, sin_t, arc, hb, rho_lo, rho_hi, lmin, lmax, jc)
            if st == FAIL:
                cls = OUTSIDE
                break
            if st == UNKNOWN:
                cls = BOUNDARY
            else:
                bits[c] |= 1 << i
        out[c] = cls


def _slacks(design: Design, grid: GridSpec, lmax: float, n_eta: int) -> tuple[float, float, float]:
    """``(arc_slack, cone_slack, eps)`` of the outside test (module docstring)."""
    lo, hi = design.eta_limits
    d_eta = math.radians(hi - lo) / (n_eta - 1) if n_eta > 1 else 0.0
    arc_slack = math.hypot(design.r, 0.5 * design.b) * 0.5 * d_eta
    xs, ys, zs = grid.axes()
    # joint cones: between arc samples the U joint moves by <= R_D d_eta/2 (base frame) and, in the
    # carriage's frame, the S joint by <= |B_xy| d_eta/2 with |B_xy| <= max |P_xy| + |u_xy|
    rb = math.hypot(max(abs(xs[0]), abs(xs[-1])) + grid.h, max(abs(ys[0]), abs(ys[-1])) + grid.h) + design.a
    cone_slack = max(math.hypot(design.r, 0.5 * design.b), rb) * 0.5 * d_eta
    return arc_slack, cone_slack, rounding_margin(lmax, (xs, ys, zs))


def cube_classes(design: Design, grid: GridSpec, args: tuple, n_eta: int, z_floor: float,
                 progress: Optional[Reporter] = None, cancel: CancelToken = None,
                 chain_bits: Optional[np.ndarray] = None) -> np.ndarray:
    """INSIDE / OUTSIDE / BOUNDARY for every cube of ``grid`` (uint8 array of the grid's shape);
    ``chain_bits`` (uint8, the grid's shape), when given, receives the chains proven inside per cube."""
    u, cos_t, sin_t, arc, hb, rho_lo, rho_hi, lmin2, lmax2, jc = args
    lmin, lmax = math.sqrt(lmin2), math.sqrt(lmax2)
    arc_slack, cone_slack, eps = _slacks(design, grid, lmax, n_eta)
    xs, ys, zs = (np.ascontiguousarray(a, dtype=np.float64) for a in grid.axes())
    out = np.zeros(grid.shape, np.uint8)
    b0, bn = _top_blocks(grid.shape, TOP_BLOCK)
    state = np.zeros((b0.shape[0], 3), np.int8)
    level = 0
    while b0.shape[0]:
        check(cancel)
        for s in range(0, b0.shape[0], 65536):
            check(cancel)
            with KERNEL_LOCK:
                _cube_kernel(b0[s:s + 65536], bn[s:s + 65536], state[s:s + 65536], xs, ys, zs, float(grid.h),
                             eps, arc_slack, cone_slack, float(z_floor), u, cos_t, sin_t, arc, hb, rho_lo, rho_hi,
                             lmin, lmax, jc)
        fail = np.any(state == FAIL, axis=1)
        inside = np.all(state == OK, axis=1)
        single = np.all(bn == 1, axis=1)
        done = fail | inside | single
        cls = np.where(fail, OUTSIDE, np.where(inside, INSIDE, BOUNDARY)).astype(np.uint8)
        _fill_kernel(b0[done], bn[done], cls[done], out)
        if chain_bits is not None:
            bits = ((state == OK) * np.array([1, 2, 4], np.int8)[None, :]).sum(axis=1).astype(np.uint8)
            _fill_kernel(b0[done], bn[done], bits[done], chain_bits)
        level += 1
        if progress is not None:
            progress(min(0.5, level / 10.0), f"volume bracket: level {level}")
        if done.all():
            break
        b0, bn, state = _split(b0[~done], bn[~done], state[~done])
    return out


#: The eight child-cube offsets (in units of the child's edge) from a cube's centre.
_CHILDREN = np.array([[dx, dy, dz] for dx in (-0.5, 0.5) for dy in (-0.5, 0.5) for dz in (-0.5, 0.5)])


def refine_boundary(design: Design, grid: GridSpec, args: tuple, n_eta: int, z_floor: float, cls: np.ndarray,
                    chain_bits: np.ndarray, levels: int, progress: Optional[Reporter] = None,
                    cancel: CancelToken = None) -> tuple[float, float, int]:
    """Split each boundary cube into 8 children ``levels`` times, classifying every child with the
    same tests as the cubes (module docstring): returns ``(inside volume found, outside volume found,
    boundary children left)``; the bracket becomes ``[V_in + inside, V_out - outside]``. A child
    inherits the chains its parent proved inside (``chain_bits``) and tests only the others."""
    u, cos_t, sin_t, arc, hb, rho_lo, rho_hi, lmin2, lmax2, jc = args
    lmin, lmax = math.sqrt(lmin2), math.sqrt(lmax2)
    arc_slack, cone_slack, eps = _slacks(design, grid, lmax, n_eta)
    idx = np.argwhere(cls == BOUNDARY)
    centres = np.asarray(grid.origin, dtype=np.float64) + grid.h * idx
    parent_bits = chain_bits[cls == BOUNDARY]
    size = float(grid.h)
    inside = outside = 0.0
    chunk = 1 << 18
    for level in range(levels):
        size *= 0.5
        left, left_bits = [], []
        for s in range(0, centres.shape[0], chunk // 8):
            check(cancel)
            kids = np.ascontiguousarray((centres[s:s + chunk // 8, None, :] + size * _CHILDREN[None]).reshape(-1, 3))
            bits = np.ascontiguousarray(np.repeat(parent_bits[s:s + chunk // 8], 8))
            out = np.empty(kids.shape[0], np.uint8)
            with KERNEL_LOCK:
                _subcube_kernel(kids, bits, size, eps, arc_slack, cone_slack, float(z_floor), u, cos_t, sin_t, arc,
                                hb, rho_lo, rho_hi, lmin, lmax, jc, out)
            inside += float(np.count_nonzero(out == INSIDE)) * size ** 3
            outside += float(np.count_nonzero(out == OUTSIDE)) * size ** 3
            left.append(kids[out == BOUNDARY])
            left_bits.append(bits[out == BOUNDARY])
        centres = np.concatenate(left) if left else np.zeros((0, 3))
        parent_bits = np.concatenate(left_bits) if left_bits else np.zeros(0, np.uint8)
        if progress is not None:
            progress(0.5 + 0.5 * (level + 1) / levels, f"volume bracket: refining the boundary, level {level + 1}")
    return inside, outside, int(centres.shape[0])


def volume_bracket(design: Design, grid: GridSpec, args: tuple, n_eta: int, z_floor: float = 0.0,
                   progress: Optional[Reporter] = None, cancel: CancelToken = None,
                   refine: int = REFINE) -> VolumeBracket:
    """The certified bracket of the continuous workspace volume over ``grid`` (module docstring):
    cubes of the grid, then ``refine`` halvings of the boundary cubes (:func:`refine_boundary`)."""
    bits = np.zeros(grid.shape, np.uint8)
    cls = cube_classes(design, grid, args, n_eta, z_floor, progress, cancel, chain_bits=bits)
    n_in = int(np.count_nonzero(cls == INSIDE))
    n_b = int(np.count_nonzero(cls == BOUNDARY))
    v = grid.voxel_volume
    add, cut, left = (refine_boundary(design, grid, args, n_eta, z_floor, cls, bits, refine, progress, cancel)
                      if refine > 0 else (0.0, 0.0, n_b))
    return VolumeBracket(volume_inner=n_in * v + add, volume_outer=(n_in + n_b) * v - cut, cubes_inside=n_in,
                         cubes_boundary=n_b, voxel=grid.h, refine=refine, boundary_left=left)


def bracket_of(result: "object", progress: Optional[Reporter] = None, cancel: CancelToken = None,
               refine: Optional[int] = None) -> VolumeBracket:
    """:func:`volume_bracket` on the grid, orientation, arc samples and joint cones of a computed
    ``kinematics.workspace.WorkspaceResult`` (``refine``: default the settings' ``bracket_refine``).

    Raises:
        ParameterError: with leg interference (the bracket does not model it).
    """
    from .workspace import _kernel_args

    r: Any = result
    if r.settings.joints.min_distance > 0.0:
        raise ParameterError("bracket", True, "not available with leg interference (leg_diameter > 0)")
    args = _kernel_args(r.design, r.settings.orientation, r.n_eta, r.settings.joints)
    return volume_bracket(r.design, r.grid, args, r.n_eta, r.settings.z_floor, progress, cancel,
                          refine=r.settings.bracket_refine if refine is None else refine)
