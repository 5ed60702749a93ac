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
"""

from __future__ import annotations

import dataclasses
import math
from typing import Any, Optional

import numpy as np
from numba import njit, prange

from .blocks import FAIL, OK, TOP_BLOCK, UNKNOWN, _fill_kernel, _split, _top_blocks, block_centre
from .design import Design
from .feasibility import _chain_excluded, _feasible_at, chain_points
from .grid import GridSpec
from .parallel import KERNEL_LOCK
from .progress import CancelToken, Reporter, check

__all__ = ["VolumeBracket", "volume_bracket", "bracket_of"]

INSIDE, OUTSIDE, BOUNDARY = 1, 2, 0


@dataclasses.dataclass(frozen=True)
class VolumeBracket:
    """``volume_inner <= V <= volume_outer`` for the continuous workspace (units^3)."""

    volume_inner: float
    volume_outer: float
    cubes_inside: int
    cubes_boundary: int
    voxel: float

    @property
    def gap(self) -> float:
        """``volume_outer - volume_inner``."""
        return self.volume_outer - self.volume_inner

    def to_dict(self) -> dict:
        """JSON form (``volume_inner``, ``volume_outer``, counts, gap)."""
        return {**dataclasses.asdict(self), "gap": self.gap}


@njit(parallel=True, cache=True, nogil=True)
def _cube_kernel(b0, bn, state, xs, ys, zs, h, eps, arc_slack, cone_slack, zfloor,
                 u, cos_t, sin_t, arc, hb, rho_lo, rho_hi, lmin, lmax, jc):
    for b in prange(b0.shape[0]):
        nx, ny, nz = bn[b, 0], bn[b, 1], bn[b, 2]
        px, py, pz = block_centre(b0, bn, b, xs, ys, zs)
        delta = 0.5 * h * math.sqrt(nx * nx + ny * ny + nz * nz)
        below = zs[b0[b, 2]] - 0.5 * h < zfloor - eps
        n = cos_t.shape[1]
        for i in range(3):
            if state[b, i] != UNKNOWN:
                continue
            b1x, b1y, b1z, b2x, b2y, b2z = chain_points(px, py, pz, u, i)
            e0 = delta + eps
            lo0 = max(lmin - e0, 0.0)
            hi0 = lmax + e0
            if _chain_excluded(b1x, b1y, b1z, b2x, b2y, b2z, hb, arc[i], rho_lo, rho_hi, lo0 * lo0, hi0 * hi0):
                state[b, i] = FAIL
                break
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
                        state[b, i] = OK
                        break
            if not some:
                state[b, i] = FAIL
                break


def cube_classes(design: Design, grid: GridSpec, args: tuple, n_eta: int, z_floor: float,
                 progress: Optional[Reporter] = None, cancel: CancelToken = None) -> np.ndarray:
    """INSIDE / OUTSIDE / BOUNDARY for every cube of ``grid`` (uint8 array of the grid's shape)."""
    u, cos_t, sin_t, arc, hb, rho_lo, rho_hi, lmin2, lmax2, jc = args
    lmin, lmax = math.sqrt(lmin2), math.sqrt(lmax2)
    lo, hi = design.eta_limits
    d_eta = math.radians(hi - lo) / (n_eta - 1) if n_eta > 1 else 0.0
    arc_slack = math.hypot(design.r, 0.5 * design.b) * 0.5 * d_eta
    xs, ys, zs = (np.ascontiguousarray(a, dtype=np.float64) for a in grid.axes())
    # joint cones: between arc samples the U joint moves by <= R_D d_eta/2 (base frame) and, in the
    # carriage's frame, the S joint by <= |B_xy| d_eta/2 with |B_xy| <= max |P_xy| + |u_xy|
    rb = math.hypot(max(abs(xs[0]), abs(xs[-1])) + grid.h, max(abs(ys[0]), abs(ys[-1])) + grid.h) + design.a
    cone_slack = max(math.hypot(design.r, 0.5 * design.b), rb) * 0.5 * d_eta
    eps = 1e-9 * max(1.0, lmax, float(np.abs(xs).max()), float(np.abs(ys).max()), float(np.abs(zs).max()))
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
        level += 1
        if progress is not None:
            progress(min(1.0, level / 5.0), f"volume bracket: level {level}")
        if done.all():
            break
        b0, bn, state = _split(b0[~done], bn[~done], state[~done])
    return out


def volume_bracket(design: Design, grid: GridSpec, args: tuple, n_eta: int, z_floor: float = 0.0,
                   progress: Optional[Reporter] = None, cancel: CancelToken = None) -> VolumeBracket:
    """The certified bracket of the continuous workspace volume over ``grid`` (module docstring)."""
    cls = cube_classes(design, grid, args, n_eta, z_floor, progress, cancel)
    n_in = int(np.count_nonzero(cls == INSIDE))
    n_b = int(np.count_nonzero(cls == BOUNDARY))
    v = grid.voxel_volume
    return VolumeBracket(volume_inner=n_in * v, volume_outer=(n_in + n_b) * v, cubes_inside=n_in,
                         cubes_boundary=n_b, voxel=grid.h)


def bracket_of(result: "object", progress: Optional[Reporter] = None, cancel: CancelToken = None) -> VolumeBracket:
    """:func:`volume_bracket` on the grid, orientation and arc samples of a computed
    ``kinematics.workspace.WorkspaceResult``."""
    from .workspace import _kernel_args

    r: Any = result
    args = _kernel_args(r.design, r.settings.orientation, r.n_eta, r.settings.joints)
    return volume_bracket(r.design, r.grid, args, r.n_eta, r.settings.z_floor, progress, cancel)
