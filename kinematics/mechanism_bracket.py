"""A certified bracket of a general mechanism's continuous workspace volume:
``volume_inner <= V <= volume_outer`` (the proof of :mod:`kinematics.bracket` extended to any carriage).

``V`` is the volume of the continuous workspace ``W``: every platform position (at the fixed
orientation, above ``z_floor``) for which every chain has SOME carriage values anywhere in its box,
not only at the samples. Each voxel is a closed cube of edge ``h`` with half-diagonal
``delta = sqrt(3) h / 2`` about its centre ``Pc``, classified per chain:

* **inside**: some carriage sample admits an ``s`` (the exact joint, (G1)-(G2) of
  :mod:`kinematics.mechanism_workspace`) with every leg in ``[lmin + delta + eps, lmax - delta - eps]``
  at ``Pc``: leg lengths are 1-Lipschitz in the position, so the same carriage values serve every
  point of the cube.
* **outside**: no sample admits an ``s`` with the legs in ``[lmin - e, lmax + e]``, ``e = delta +
  e_c + eps``, or the chain's balls grown by ``e`` reject ``Pc``. ``e_c`` bounds how far a base
  joint moves between a carriage value and the nearest sample: the sum over the chain's sampled
  joints of half their spacing times their lever, where a sampled prismatic joint's lever is 1 and a
  revolute joint's is ``L_m = max_j |D0_j| + sum of max(|lo|, |hi|) over the prismatic joints after
  it`` (in the frame after the joints before ``m`` the base joint is the rest of the chain applied to
  ``D0_j``: rotations about that frame's origin keep norms, translations add at most their stroke),
  in radians. Proof: if a point ``P`` of the cube were served by carriage values ``q``, the nearest
  sample ``q_k`` (the same ``s``) puts every base joint within ``e_c`` of where ``q`` puts it, and
  ``|P - Pc| <= delta``, so every leg length at ``(Pc, q_k, s)`` is within ``e`` of its length at
  ``(P, q, s)``: sample ``k`` would pass the relaxed test. The balls contain every base joint of the
  samples, so those of the continuous box lie within ``e_c`` of them.

A cube is inside ``W`` when every chain is inside, outside when some chain is outside, else a
boundary cube; ``N_in h^3 <= V <= (N_in + N_boundary) h^3`` provided ``W`` lies in the grid, which
is checked: the grid is grown by ``ceil(max e_c / h) + 1`` voxels (never below the floor) and every
cube of its outer layer (but the floor) must be outside, else ``volume_outer`` is ``inf``. Joint
cones are refused (their axes turn with the revolute joints: not part of this proof yet).
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
from numba import njit, prange

from .design import ParameterError
from .grid import GridSpec
from .mechanism import Chain, Mechanism
from .mechanism_workspace import _BOUND_EPS, KernelTables, _chain_ok, _chain_out, exact_joint, joint_sample_values


@dataclasses.dataclass(frozen=True)
class GeneralBracket:
    """``volume_inner <= V <= volume_outer`` and the cube counts (``outer`` is ``inf`` when ``W`` may
    leave the grid)."""

    volume_inner: float
    volume_outer: float
    inside: int
    boundary: int
    grid: GridSpec


def chain_slack(chain: Chain, eta_step: float, length_step: float) -> float:
    """``e_c`` of the module docstring: how far a base joint can be from the nearest sample's."""
    m_star = exact_joint(chain)
    values = joint_sample_values(chain, eta_step, length_step)
    reach = max(float(np.linalg.norm(leg.base)) for leg in chain.legs)
    slack = 0.0
    for m, (joint, vals) in enumerate(zip(chain.carriage, values)):
        if m == m_star or len(vals) < 2:
            continue
        spacing = float(vals[1] - vals[0])
        if joint.type == "prismatic":
            slack += 0.5 * spacing
        else:
            lever = reach + sum(max(abs(j.range[0]), abs(j.range[1])) for j in chain.carriage[m + 1:]
                                if j.type == "prismatic")
            slack += 0.5 * math.radians(spacing) * lever
    return slack


@njit(parallel=True, cache=True, nogil=True)
def _bracket_kernel(xs, ys, zs, delta_t, e_out, lmin2t, lmax2t, lmin2r, lmax2r, k0, nk, l0, nl, s_lo, s_hi, w,
                    base, u_axis, k_u, plat, s_axis, k_s, lmin2, lmax2, centre, out2, in2, kb0, blk_centre,
                    blk_out2, blk_in2, state):
    """``state[ix, iy, iz]``: 1 inside, 0 outside, 2 boundary (module docstring); ``e_out`` per chain."""
    n_chains = k0.shape[0]
    nx, ny, nz = xs.shape[0], ys.shape[0], zs.shape[0]
    for col in prange(nx * ny):
        ix = col // ny
        iy = col - ix * ny
        gap_lo = np.empty(8)
        gap_hi = np.empty(8)
        start = np.empty(n_chains, np.int64)
        for c in range(n_chains):
            start[c] = nk[c] // 2
        for iz in range(nz):
            st = 1
            for c in range(n_chains):
                if _chain_out(xs[ix], ys[iy], zs[iz], e_out[c], e_out[c], c, k0, nk, l0, nl, s_lo, s_hi, w, base,
                              u_axis, k_u, plat, s_axis, k_s, lmin2r[c], lmax2r[c], centre, out2, in2, kb0,
                              blk_centre, blk_out2, blk_in2, gap_lo, gap_hi):
                    st = 0
                    break
                if st == 1 and not _chain_ok(xs[ix], ys[iy], zs[iz], c, start, k0, nk, l0, nl, s_lo, s_hi, w, base,
                                            u_axis, k_u, plat, s_axis, k_s, lmin2t, lmax2t, centre, out2, in2, kb0,
                                            blk_centre, blk_out2, blk_in2, gap_lo, gap_hi, delta_t):
                    st = 2
            state[ix, iy, iz] = st


def general_bracket(mech: Mechanism, tables: KernelTables, grid: GridSpec, eta_step: float, length_step: float,
                    z_floor: float) -> GeneralBracket:
    """The bracket of the module docstring around the workspace computed on ``grid``."""
    if any(leg.u_cone is not None or leg.s_cone is not None for _, _, leg in mech.legs):
        raise ParameterError("bracket", True, "not available with joint cones (u_cone, s_cone) on a general "
                                              "mechanism")
    h = grid.h
    slack = np.array([chain_slack(c, eta_step, length_step) for c in mech.chains])
    pad = int(math.ceil(float(slack.max(initial=0.0)) / h)) + 1
    lo = (grid.lo[0] - pad * h, grid.lo[1] - pad * h, max(z_floor, grid.lo[2] - pad * h))
    hi = (grid.hi[0] + pad * h, grid.hi[1] + pad * h, grid.hi[2] + pad * h)
    big = GridSpec.from_bounds(lo, hi, h)
    xs, ys, zs = big.axes()
    lmin = np.sqrt(tables.lmin2)
    lmax = np.sqrt(tables.lmax2)
    eps = _BOUND_EPS * (1.0 + float(lmax.max()) + float(np.abs(tables.base).max(initial=0.0)))
    delta = math.sqrt(3.0) * 0.5 * h
    delta_t = delta + eps
    lmin2t = (lmin + delta_t) ** 2
    lmax2t = np.where(lmax - delta_t > 0.0, (lmax - delta_t) ** 2, -1.0)
    e_out = delta + slack + eps                                   # per chain
    legs_chain = np.array([c for c, _, _ in mech.legs])
    e_leg = e_out[legs_chain]
    lmin2r = np.where(lmin - e_leg > 0.0, lmin - e_leg, 0.0) ** 2
    lmax2r = (lmax + e_leg) ** 2
    # per chain rows: the kernel reads row c (the legs of other chains are never read)
    lmin2r_c = np.ascontiguousarray(np.broadcast_to(lmin2r, (len(mech.chains), len(lmin))))
    lmax2r_c = np.ascontiguousarray(np.broadcast_to(lmax2r, (len(mech.chains), len(lmin))))
    state = np.zeros(big.shape, np.uint8)
    _bracket_kernel(xs, ys, zs, delta_t, e_out, lmin2t, lmax2t, lmin2r_c, lmax2r_c, *tables.args(), state)
    inside = int((state == 1).sum())
    boundary = int((state == 2).sum())
    vv = h ** 3
    rim = np.zeros(big.shape, bool)
    rim[[0, -1], :, :] = True
    rim[:, [0, -1], :] = True
    rim[:, :, -1] = True
    if big.lo[2] > z_floor + 1e-9:  # the bottom is not the floor: W must not cross it either
        rim[:, :, 0] = True
    contained = not np.any(state[rim] != 0)
    return GeneralBracket(inside * vv, (inside + boundary) * vv if contained else math.inf, inside, boundary, big)
