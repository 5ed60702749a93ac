"""Constant-orientation position workspace and inverse kinematics of any
:class:`~kinematics.mechanism.Mechanism` (a description: chains of carriage joints carrying U-P-S legs).

**Definition.** With the carriage transform ``T_c(q)`` of (M1) and the legs of (M2), a platform
position ``P`` at the fixed rotation ``R`` is reachable when every chain ``c`` has carriage values
``q`` in its box with every leg ``j`` of the chain in ``[lmin_j, lmax_j]`` and inside its joint
cones (:mod:`kinematics.joints` (J1), about the leg's own axes). The voxel grid, the result and
the default-bounds guarantee (the box never clips the workspace) are those of
:mod:`kinematics.workspace`; ``R = Rot(reference) Rz(psi) Ry(theta) Rx(phi)``.

**Exact in one prismatic joint.** In chain ``c`` take the prismatic joint ``m*`` of longest stroke
(the later one on a tie) with value ``s`` in ``[s_lo, s_hi]``. With ``(A, a) = T_1 ... T_{m*-1}``
(the joints before it, at their values) every leg's base joint moves on a line along the SAME
unit direction ``w = A u_{m*}``:

    D_j(q) = D_j(q|s=0) + s w .                                                          (G1)

With ``v_j = B_j - D_j(q|s=0)``, ``p_j = v_j . w`` and ``q_j = |v_j|^2 - p_j^2``

    l_j(s)^2 = (s - p_j)^2 + q_j ,                                                       (G2)

quadratic in ``s`` as the paper's (F1) is in ``rho``: ``lmin^2 <= l^2 <= lmax^2`` holds on the
closed interval ``|s - p_j| <= sqrt(lmax^2 - q_j)`` minus the open gap ``|s - p_j| <
sqrt(lmin^2 - q_j)`` (no gap when ``q_j >= lmin^2``; a fixed-length leg leaves the two end points).
A joint cone ``a . (v_j - s w) >= cos(theta) l_j(s)`` (``a`` the U axis turned by the carriage or
the S axis turned by ``R``) is one interval of ``s`` (:func:`kinematics.feasibility.cone_interval`).
The chain is feasible at given values of its other joints iff ``[s_lo, s_hi]`` cut by every leg's
interval and cones, minus every leg's gap, is non-empty: the smallest point of such a set is its
lower end or a gap's upper end, so these at most seven candidates decide it exactly.

**Sampled in the others.** The chain's other joints take equally spaced values including both ends:
``ceil(range / eta_step) + 1`` for a revolute joint (degrees) and ``ceil(range / length_step) + 1``
for a second prismatic joint. As in :mod:`kinematics.feasibility` the error is one-sided (an inner
approximation, confined to poses whose feasible set of those joints is narrower than a step). A
chain without a prismatic joint (a fixed base, or a revolute only) is sampled in every joint and
tested at ``s = 0`` (``[s_lo, s_hi] = [0, 0]``).

**Whole-chain bound.** Over the chain's samples and both ends of ``[s_lo, s_hi]`` every base joint
``D_j`` stays in a ball ``(c_j, rho_j)`` (the segment of (G1) lies in the ball of its end points), so
``|B_j - c_j| > lmax_j + rho_j`` or ``|B_j - c_j| < lmin_j - rho_j`` rejects the chain without
sampling (both relaxed by a rounding margin so the bound never contradicts the sample test). The
same bound over each block of :data:`BLOCK` consecutive samples skips whole blocks of the search.
The chain's balls give the default box: ``P`` in ``c_j - R u_j +- (lmax_j + rho_j)`` for every leg.

**Blocks.** ``method="blocks"`` (the default) decides cubes of :data:`CUBE`^3 voxels, then their
halves, whole: with ``r`` the half-diagonal of a cube's voxel centres, every leg length is
1-Lipschitz and every cone function ``a . v - k |v|`` is ``(1 + k)``-Lipschitz in ``P``, so a sample
and ``s`` that pass at the cube's centre with the limits and cones TIGHTENED by ``r`` pass at every
voxel of it, and a sample that passes at some voxel passes at the centre with them RELAXED by ``r``
(both with a rounding margin): "some chain has no sample passing relaxed" makes the cube unreachable,
"every chain has a sample passing tightened" reachable (or, for a chain of one leg without cones, the
bracket's one-leg test: its length's range over the exact joint, shrunk by ``r``, meets its limits;
the comment before :func:`general_bracket`); the other cubes are tested voxel by voxel.
The voxels are those of ``method="dense"`` (every voxel tested; tested equal).

**The paper's mechanism** (a description equal to :func:`kinematics.presets.paper` of some
:class:`~kinematics.design.Design`, reference zero) is routed to :func:`kinematics.workspace.
compute_workspace` with that design: voxel-identical to today's model at today's speed. The general
engine decides the same arc samples and the same exact test in ``d`` on it (``d = s``), so it agrees
with that engine up to floating-point rounding at voxel centres lying on a leg limit (tested).

``settings.bracket`` adds the certified bracket of :func:`general_bracket` (its proof is in the
comment above it; ``settings.bracket_refine`` halvings of the boundary cubes; not with cones). A leg
``diameter`` adds leg interference (:mod:`kinematics.mechanism_interference`: the reachable voxels are filtered by its
test; not with the bracket). What the general engine does not compute (refused by name): the per-voxel
chain masks of ``settings.diagnostics`` (:mod:`kinematics.mechanism_diagnostics` names the binding
limits instead) and :class:`~kinematics.joints.Joints` options (a description carries its own cones).
"""

from __future__ import annotations

import dataclasses
import math
import time
from collections.abc import Sequence

import numpy as np
from numba import njit, prange

from .bracket import VolumeBracket
from .design import Design, ParameterError
from .feasibility import cone_interval
from .grid import GridSpec
from .joints import Joints
from .mechanism import LENGTH_STEP_RANGE, Chain, Mechanism, check_length_step, platform_rotation  # noqa: F401 - re-exported
from .parallel import KERNEL_LOCK
from .presets import paper
from .progress import CancelToken, ProgressFn, Reporter, check
from .workspace import WorkspaceResult, WorkspaceSettings, compute_workspace

#: Most carriage samples of one chain (the product of its sampled joints' counts).
MAX_CHAIN_SAMPLES = 200_000
#: Relative rounding margin of the whole-chain bound.
_BOUND_EPS = 1e-9
#: Consecutive carriage samples sharing one bound (a block the search skips when its balls reject).
BLOCK = 8
#: Edge, in voxels, of the cubes the blocks engine decides whole (then their halves).
CUBE = 4
#: Why a general mechanism has no certified bracket (the refusal of ``bracket`` and the explorer's words).
NO_BRACKET_CONES = "not available with joint cones (u_cone, s_cone): their axes turn with the carriage's joints"
NO_BRACKET_DIAMETERS = "not available with leg diameters (the bracket does not model leg interference)"


def exact_joint(chain: Chain) -> int | None:
    """Index of the chain's exactly-solved prismatic joint: longest stroke, the later one on a tie
    (``None`` without a prismatic joint)."""
    best = None
    for m, joint in enumerate(chain.carriage):
        if joint.type == "prismatic" and (best is None or
                                          joint.range[1] - joint.range[0] >= chain.carriage[best].range[1]
                                          - chain.carriage[best].range[0]):
            best = m
    return best


def joint_sample_values(chain: Chain, eta_step: float, length_step: float) -> list[np.ndarray]:
    """The values each joint takes: ``[0]`` for the exact joint, equally spaced (both ends) for the others."""
    m_star = exact_joint(chain)
    out = []
    for m, joint in enumerate(chain.carriage):
        lo, hi = joint.range
        if m == m_star:
            out.append(np.zeros(1))
            continue
        step = eta_step if joint.type == "revolute" else length_step
        n = int(math.ceil((hi - lo) / step - 1e-12)) + 1 if hi > lo else 1
        out.append(np.linspace(lo, hi, n) if n > 1 else np.array([lo]))
    return out


@dataclasses.dataclass(frozen=True)
class ChainTables:
    """One chain's samples: the joint values ``q`` (K, k) (the exact joint at 0), the legs' base
    joints ``D_j(q|s=0)`` (K, n, 3), the exact joint's direction ``w`` (K, 3), the carriage rotations
    (K, 3, 3), the exact joint's index and stroke ``[s_lo, s_hi]`` (``[0, 0]`` without one)."""

    q: np.ndarray
    base: np.ndarray
    w: np.ndarray
    rot: np.ndarray
    exact: int | None
    s_range: tuple[float, float]


def chain_tables(chain: Chain, eta_step: float, length_step: float) -> ChainTables:
    """(G1) on the chain's sample grid (see the module docstring)."""
    values = joint_sample_values(chain, eta_step, length_step)
    count = int(np.prod([len(v) for v in values])) if values else 1
    if count > MAX_CHAIN_SAMPLES:
        raise ParameterError("eta_step/length_step", (eta_step, length_step),
                             f"steps giving at most {MAX_CHAIN_SAMPLES:,} carriage samples per chain "
                             f"(these give {count:,})")
    if values:
        mesh = np.meshgrid(*values, indexing="ij")
        combos = np.stack([g.ravel() for g in mesh], axis=1)
    else:
        combos = np.zeros((1, 0))
    m_star = exact_joint(chain)
    legs = np.array([leg.base for leg in chain.legs], float)
    # (M1) for every sample at once, T <- T T_m; w = the rotation before m* times its axis (G1)
    rots = np.broadcast_to(np.eye(3), (len(combos), 3, 3)).copy()
    trans = np.zeros((len(combos), 3))
    w = np.zeros((len(combos), 3))
    for m, joint in enumerate(chain.carriage):
        axis = np.asarray(joint.axis, float)
        if m == m_star:
            w = rots @ axis
        if joint.type == "revolute":
            ang = np.radians(combos[:, m])
            kx = np.array([[0.0, -axis[2], axis[1]], [axis[2], 0.0, -axis[0]], [-axis[1], axis[0], 0.0]])
            rots = rots @ (np.eye(3)[None] + np.sin(ang)[:, None, None] * kx[None]
                           + (1.0 - np.cos(ang))[:, None, None] * (kx @ kx)[None])
        else:
            trans = trans + combos[:, m, None] * (rots @ axis)
    base = np.einsum("lc,kdc->kld", legs, rots) + trans[:, None, :]
    if m_star is None:
        w[:, 0] = 1.0
        s_range = (0.0, 0.0)
    else:
        s_range = chain.carriage[m_star].range
    return ChainTables(combos, base, np.ascontiguousarray(w), rots, m_star, s_range)


@dataclasses.dataclass(frozen=True)
class KernelTables:
    """The compiled test's constants for one mechanism at one platform rotation (flattened over
    chains: chain ``c`` owns samples ``k0[c] .. k0[c] + nk[c]`` and legs ``l0[c] .. l0[c] + nl[c]``)."""

    k0: np.ndarray
    nk: np.ndarray
    l0: np.ndarray
    nl: np.ndarray
    s_lo: np.ndarray
    s_hi: np.ndarray
    w: np.ndarray        # (K, 3)
    base: np.ndarray     # (K, 6, 3): D_j(q|s=0), legs of other chains unused
    u_axis: np.ndarray   # (K, 6, 3): U-cone axes turned by the carriage
    k_u: np.ndarray      # (6,): cos(theta_U), -1 for none
    plat: np.ndarray     # (6, 3): R u_j
    s_axis: np.ndarray   # (6, 3): S-cone axes turned by R
    k_s: np.ndarray      # (6,)
    lmin2: np.ndarray
    lmax2: np.ndarray
    centre: np.ndarray   # (6, 3): the whole-chain bound's balls
    out2: np.ndarray     # (6,): reject when |B - c|^2 > out2
    in2: np.ndarray      # (6,): reject when |B - c|^2 < in2
    kb0: np.ndarray      # (C,): chain c's first block
    blk_centre: np.ndarray  # (blocks, 6, 3): the same bound per block of BLOCK samples
    blk_out2: np.ndarray    # (blocks, 6)
    blk_in2: np.ndarray     # (blocks, 6)
    chains: tuple[ChainTables, ...]

    def args(self) -> tuple:
        return (self.k0, self.nk, self.l0, self.nl, self.s_lo, self.s_hi, self.w, self.base, self.u_axis,
                self.k_u, self.plat, self.s_axis, self.k_s, self.lmin2, self.lmax2, self.centre, self.out2,
                self.in2, self.kb0, self.blk_centre, self.blk_out2, self.blk_in2)


def kernel_tables(mech: Mechanism, rotation: np.ndarray, eta_step: float = 0.5,
                  length_step: float = 1.0) -> KernelTables:
    """Build :class:`KernelTables` (the sample grids of every chain, (G1), cones and bounds)."""
    rotation = np.asarray(rotation, float)
    chains = tuple(chain_tables(c, eta_step, length_step) for c in mech.chains)
    n_legs = len(mech.legs)
    total = sum(len(t.q) for t in chains)
    k0 = np.zeros(len(chains), np.int64)
    nk = np.zeros(len(chains), np.int64)
    l0 = np.zeros(len(chains), np.int64)
    nl = np.zeros(len(chains), np.int64)
    s_lo = np.zeros(len(chains))
    s_hi = np.zeros(len(chains))
    w = np.zeros((total, 3))
    base = np.zeros((total, n_legs, 3))
    u_axis = np.zeros((total, n_legs, 3))
    k_u = -np.ones(n_legs)
    k_s = -np.ones(n_legs)
    s_axis = np.zeros((n_legs, 3))
    plat = np.array([leg.platform for _, _, leg in mech.legs], float) @ rotation.T
    lmin = np.array([leg.length[0] for _, _, leg in mech.legs])
    lmax = np.array([leg.length[1] for _, _, leg in mech.legs])
    centre = np.zeros((n_legs, 3))
    radius = np.zeros(n_legs)
    n_blocks = [-(-len(t.q) // BLOCK) for t in chains]
    kb0 = np.concatenate([[0], np.cumsum(n_blocks)[:-1]]).astype(np.int64)
    blk_centre = np.zeros((sum(n_blocks), n_legs, 3))
    blk_radius = np.zeros((sum(n_blocks), n_legs))
    blk_lmin = np.zeros((sum(n_blocks), n_legs))
    blk_lmax = np.zeros((sum(n_blocks), n_legs))
    k, j = 0, 0
    for c, (chain, tab) in enumerate(zip(mech.chains, chains)):
        K, n = len(tab.q), len(chain.legs)
        k0[c], nk[c], l0[c], nl[c] = k, K, j, n
        s_lo[c], s_hi[c] = tab.s_range
        w[k:k + K] = tab.w
        base[k:k + K, j:j + n] = tab.base
        for jj, leg in enumerate(chain.legs):
            if leg.u_cone is not None:
                u_axis[k:k + K, j + jj] = tab.rot @ np.asarray(leg.u_cone.axis, float)
                k_u[j + jj] = math.cos(math.radians(leg.u_cone.angle))
            if leg.s_cone is not None:
                s_axis[j + jj] = rotation @ np.asarray(leg.s_cone.axis, float)
                k_s[j + jj] = math.cos(math.radians(leg.s_cone.angle))
            ends = np.concatenate([tab.base[:, jj] + tab.s_range[0] * tab.w, tab.base[:, jj] + tab.s_range[1] * tab.w])
            lo_, hi_ = ends.min(axis=0), ends.max(axis=0)
            centre[j + jj] = 0.5 * (lo_ + hi_)
            radius[j + jj] = float(np.sqrt(((ends - centre[j + jj]) ** 2).sum(axis=1)).max())
            # per block of BLOCK samples (the last block padded with its last sample)
            nb = n_blocks[c]
            pad = np.concatenate([np.arange(K), np.full(nb * BLOCK - K, K - 1)])
            d = tab.base[pad, jj].reshape(nb, BLOCK, 3)
            ww = tab.w[pad].reshape(nb, BLOCK, 3)
            ends_b = np.concatenate([d + tab.s_range[0] * ww, d + tab.s_range[1] * ww], axis=1)
            mid = 0.5 * (ends_b.min(axis=1) + ends_b.max(axis=1))
            blk_centre[kb0[c]:kb0[c] + nb, j + jj] = mid
            blk_radius[kb0[c]:kb0[c] + nb, j + jj] = np.sqrt(((ends_b - mid[:, None]) ** 2).sum(axis=2)).max(axis=1)
            blk_lmin[kb0[c]:kb0[c] + nb, j + jj] = leg.length[0]
            blk_lmax[kb0[c]:kb0[c] + nb, j + jj] = leg.length[1]
        k, j = k + K, j + n
    scale = 1.0 + float(np.abs(base).max(initial=0.0)) + float(lmax.max()) + float(np.abs(plat).max())
    eps = _BOUND_EPS * scale
    out2 = (lmax + radius + eps) ** 2
    inner = lmin - radius - eps
    in2 = np.where(inner > 0.0, inner, 0.0) ** 2
    blk_out2 = (blk_lmax + blk_radius + eps) ** 2
    blk_inner = blk_lmin - blk_radius - eps
    blk_in2 = np.where(blk_inner > 0.0, blk_inner, 0.0) ** 2
    c_ = np.ascontiguousarray
    return KernelTables(k0, nk, l0, nl, s_lo, s_hi, c_(w), c_(base), c_(u_axis), k_u, c_(plat), c_(s_axis), k_s,
                        lmin ** 2, lmax ** 2, c_(centre), out2, in2, kb0, c_(blk_centre), c_(blk_out2),
                        c_(blk_in2), chains)


# --------------------------------------------------------------------------------------------
# compiled test


@njit(cache=True, forceinline=True)
def _free(x, gap_lo, gap_hi, ng):
    for g in range(ng):
        if gap_lo[g] < x < gap_hi[g]:
            return False
    return True


@njit(cache=True)
def _sample_feasible(px, py, pz, k, l0, nl, s_lo, s_hi, w, base, u_axis, k_u, plat, s_axis, k_s,
                     lmin2, lmax2, gap_lo, gap_hi, shift):
    """The exact test in ``s`` of one chain at its carriage sample ``k`` (module docstring); ``shift > 0``
    tightens each cone by ``(1 + k) shift`` (the blocks engine's test for a whole cube, with the leg
    limits tightened by the caller)."""
    wx, wy, wz = w[k, 0], w[k, 1], w[k, 2]
    lo, hi = s_lo, s_hi
    ng = 0
    for jj in range(nl):
        j = l0 + jj
        vx = px + plat[j, 0] - base[k, j, 0]
        vy = py + plat[j, 1] - base[k, j, 1]
        vz = pz + plat[j, 2] - base[k, j, 2]
        p = vx * wx + vy * wy + vz * wz
        q = vx * vx + vy * vy + vz * vz - p * p
        if q < 0.0:
            q = 0.0
        if q > lmax2[j]:
            return False
        ro = math.sqrt(lmax2[j] - q)
        lo = max(lo, p - ro)
        hi = min(hi, p + ro)
        if lo > hi:
            return False
        if lmin2[j] > q:
            ri = math.sqrt(lmin2[j] - q)
            gap_lo[ng] = p - ri
            gap_hi[ng] = p + ri
            ng += 1
        if k_u[j] > -1.0:
            ax, ay, az = u_axis[k, j, 0], u_axis[k, j, 1], u_axis[k, j, 2]
            a0, a1 = cone_interval(ax * vx + ay * vy + az * vz - (1.0 + k_u[j]) * shift,
                                   -(ax * wx + ay * wy + az * wz), k_u[j], p, q)
            lo = max(lo, a0)
            hi = min(hi, a1)
            if lo > hi:
                return False
        if k_s[j] > -1.0:
            ax, ay, az = s_axis[j, 0], s_axis[j, 1], s_axis[j, 2]
            a0, a1 = cone_interval(ax * vx + ay * vy + az * vz - (1.0 + k_s[j]) * shift,
                                   -(ax * wx + ay * wy + az * wz), k_s[j], p, q)
            lo = max(lo, a0)
            hi = min(hi, a1)
            if lo > hi:
                return False
    if _free(lo, gap_lo, gap_hi, ng):
        return True
    for g in range(ng):
        x = gap_hi[g]
        if lo <= x <= hi and _free(x, gap_lo, gap_hi, ng):
            return True
    return False


@njit(cache=True, forceinline=True)
def _balls_reject(px, py, pz, g, l0, nl, plat, centre, out2, in2):
    """The bound of ball row ``g`` (a chain's, or a block's): True when some leg's ball rejects ``P``."""
    for jj in range(nl):
        j = l0 + jj
        dx = px + plat[j, 0] - centre[g, j, 0]
        dy = py + plat[j, 1] - centre[g, j, 1]
        dz = pz + plat[j, 2] - centre[g, j, 2]
        d2 = dx * dx + dy * dy + dz * dz
        if d2 > out2[g, j] or d2 < in2[g, j]:
            return True
    return False


@njit(cache=True)
def _chain_ok(px, py, pz, c, start, k0, nk, l0, nl, s_lo, s_hi, w, base, u_axis, k_u, plat, s_axis, k_s,
              lmin2, lmax2, centre, out2, in2, kb0, blk_centre, blk_out2, blk_in2, gap_lo, gap_hi, shift):
    """Whether chain ``c`` serves ``P``: the whole-chain bound, the sample ``start[c]`` that served
    last, then the blocks of samples outward from its block, each skipped when its bound rejects
    (``start[c]`` is updated to the sample that served)."""
    for jj in range(nl[c]):
        j = l0[c] + jj
        dx = px + plat[j, 0] - centre[j, 0]
        dy = py + plat[j, 1] - centre[j, 1]
        dz = pz + plat[j, 2] - centre[j, 2]
        d2 = dx * dx + dy * dy + dz * dz
        if d2 > out2[j] or d2 < in2[j]:
            return False
    n = nk[c]
    s0 = start[c]
    if _sample_feasible(px, py, pz, k0[c] + s0, l0[c], nl[c], s_lo[c], s_hi[c], w, base, u_axis, k_u, plat,
                        s_axis, k_s, lmin2, lmax2, gap_lo, gap_hi, shift):
        return True
    nb = (n + BLOCK - 1) // BLOCK
    b0 = s0 // BLOCK
    for step in range(2 * nb):
        off = (step + 1) // 2
        b = b0 + off if step % 2 == 1 else b0 - off
        if b < 0 or b >= nb:
            if off > nb:
                break
            continue
        if _balls_reject(px, py, pz, kb0[c] + b, l0[c], nl[c], plat, blk_centre, blk_out2, blk_in2):
            continue
        for kk in range(b * BLOCK, min(b * BLOCK + BLOCK, n)):
            if kk != s0 and _sample_feasible(px, py, pz, k0[c] + kk, l0[c], nl[c], s_lo[c], s_hi[c], w, base,
                                             u_axis, k_u, plat, s_axis, k_s, lmin2, lmax2, gap_lo, gap_hi, shift):
                start[c] = kk
                return True
    return False


@njit(parallel=True, cache=True, nogil=True)
def _columns_kernel(col_ix, col_iy, xs, ys, zs, k0, nk, l0, nl, s_lo, s_hi, w, base, u_axis, k_u, plat,
                    s_axis, k_s, lmin2, lmax2, centre, out2, in2, kb0, blk_centre, blk_out2, blk_in2, out):
    """Occupancy of the columns ``(col_ix, col_iy)``, each walked upward with a warm start per chain;
    the chain that failed last is tested first."""
    n_chains = k0.shape[0]
    for col in prange(col_ix.shape[0]):
        ix = col_ix[col]
        iy = col_iy[col]
        gap_lo = np.empty(8)
        gap_hi = np.empty(8)
        start = np.empty(n_chains, np.int64)
        for c in range(n_chains):
            start[c] = nk[c] // 2
        first = 0
        for iz in range(zs.shape[0]):
            ok = True
            for cc in range(n_chains):
                c = (first + cc) % n_chains
                if not _chain_ok(xs[ix], ys[iy], zs[iz], c, start, k0, nk, l0, nl, s_lo, s_hi, w, base, u_axis,
                                 k_u, plat, s_axis, k_s, lmin2, lmax2, centre, out2, in2, kb0, blk_centre,
                                 blk_out2, blk_in2, gap_lo, gap_hi, 0.0):
                    ok = False
                    first = c
                    break
            out[ix, iy, iz] = ok


@njit(parallel=True, cache=True, nogil=True)
def _points_kernel(points, k0, nk, l0, nl, s_lo, s_hi, w, base, u_axis, k_u, plat, s_axis, k_s,
                   lmin2, lmax2, centre, out2, in2, kb0, blk_centre, blk_out2, blk_in2, out):
    n_chains = k0.shape[0]
    for p in prange(points.shape[0]):
        gap_lo = np.empty(8)
        gap_hi = np.empty(8)
        start = np.empty(n_chains, np.int64)
        for c in range(n_chains):
            start[c] = nk[c] // 2
        ok = True
        for c in range(n_chains):
            if not _chain_ok(points[p, 0], points[p, 1], points[p, 2], c, start, k0, nk, l0, nl, s_lo, s_hi, w,
                             base, u_axis, k_u, plat, s_axis, k_s, lmin2, lmax2, centre, out2, in2, kb0,
                             blk_centre, blk_out2, blk_in2, gap_lo, gap_hi, 0.0):
                ok = False
                break
        out[p] = ok


@njit(cache=True)
def _chain_out(px, py, pz, r, rt, c, k0, nk, l0, nl, s_lo, s_hi, w, base, u_axis, k_u, plat, s_axis, k_s,
               lmin2r, lmax2r, centre, out2, in2, kb0, blk_centre, blk_out2, blk_in2, gap_lo, gap_hi):
    """True when chain ``c`` fails at every point within ``r`` of ``P``: its balls grown by ``r``
    reject ``P``, or every sample (of the blocks those balls do not reject) fails the test with its leg
    limits and cones relaxed by ``rt`` (``lmin2r``, ``lmax2r``): a sample that served a point within
    ``r`` would pass it (lengths are 1-Lipschitz and cones (1 + k)-Lipschitz in ``P``)."""
    for jj in range(nl[c]):
        j = l0[c] + jj
        dx = px + plat[j, 0] - centre[j, 0]
        dy = py + plat[j, 1] - centre[j, 1]
        dz = pz + plat[j, 2] - centre[j, 2]
        d = math.sqrt(dx * dx + dy * dy + dz * dz)
        if d > math.sqrt(out2[j]) + r or d < math.sqrt(in2[j]) - r:
            return True
    n = nk[c]
    nb = (n + BLOCK - 1) // BLOCK
    for b in range(nb):
        g = kb0[c] + b
        rejected = False
        for jj in range(nl[c]):
            j = l0[c] + jj
            dx = px + plat[j, 0] - blk_centre[g, j, 0]
            dy = py + plat[j, 1] - blk_centre[g, j, 1]
            dz = pz + plat[j, 2] - blk_centre[g, j, 2]
            d = math.sqrt(dx * dx + dy * dy + dz * dz)
            if d > math.sqrt(blk_out2[g, j]) + r or d < math.sqrt(blk_in2[g, j]) - r:
                rejected = True
                break
        if rejected:
            continue
        for kk in range(b * BLOCK, min(b * BLOCK + BLOCK, n)):
            if _sample_feasible(px, py, pz, k0[c] + kk, l0[c], nl[c], s_lo[c], s_hi[c], w, base, u_axis, k_u, plat,
                                s_axis, k_s, lmin2r, lmax2r, gap_lo, gap_hi, -rt):
                return False
    return True


@njit(cache=True)
def _cube_state(px, py, pz, lv, r, rt, lmin2t, lmax2t, lmin2r, lmax2r, start, k0, nk, l0, nl, s_lo, s_hi, w, base,
                u_axis, k_u, plat, s_axis, k_s, lmin2, lmax2, centre, out2, in2, kb0, blk_centre, blk_out2, blk_in2,
                gap_lo, gap_hi):
    """0: every voxel of the cube (level ``lv``, centre ``P``) is unreachable; 1: every voxel is
    reachable; 2: undecided (see :func:`_blocks_kernel`)."""
    state = 1
    for c in range(k0.shape[0]):
        if _chain_out(px, py, pz, r[lv], rt[lv], c, k0, nk, l0, nl, s_lo, s_hi, w, base, u_axis, k_u, plat, s_axis,
                      k_s, lmin2r[lv], lmax2r[lv], centre, out2, in2, kb0, blk_centre, blk_out2, blk_in2, gap_lo,
                      gap_hi):
            return 0
        if state == 1 and not _chain_ok(px, py, pz, c, start, k0, nk, l0, nl, s_lo, s_hi, w, base, u_axis, k_u,
                                        plat, s_axis, k_s, lmin2t[lv], lmax2t[lv], centre, out2, in2, kb0,
                                        blk_centre, blk_out2, blk_in2, gap_lo, gap_hi, rt[lv]) \
                and not (nl[c] == 1 and k_u[l0[c]] <= -1.0 and k_s[l0[c]] <= -1.0
                         and _single_leg_inside(px, py, pz, c, k0, nk, l0, s_lo, s_hi, w, base, plat, lmin2, lmax2,
                                                rt[lv])):
            state = 2
    return state


@njit(parallel=True, cache=True, nogil=True)
def _blocks_kernel(cols, m, xs, ys, zs, r, rt, lmin2t, lmax2t, lmin2r, lmax2r, k0, nk, l0, nl, s_lo, s_hi, w,
                   base, u_axis, k_u, plat, s_axis, k_s, lmin2, lmax2, centre, out2, in2, kb0, blk_centre, blk_out2,
                   blk_in2, out):
    """Cubes of ``m^3`` voxels (``m`` even), by columns of cubes ``cols`` (cube indices ``(cx, cy)``),
    then their halves: at level ``lv`` (0: edge ``m``, 1: edge ``m/2``) ``r[lv]`` is the half-diagonal
    of a cube's voxel centres and ``rt[lv] = r[lv] +`` a rounding margin. A cube is unreachable when
    some chain is out for every point within ``r`` of its centre (:func:`_chain_out`, limits relaxed by
    ``rt``), reachable when every chain passes the test at its centre with its leg limits
    (``lmin2t``, ``lmax2t``) and cones tightened by ``rt`` (the same sample and ``s`` then serve every
    voxel: lengths are 1-Lipschitz and cones (1 + k)-Lipschitz in ``P``), or, for a chain of one leg
    without cones, passes the one-leg test of the bracket with ``rt`` (:func:`_single_leg_inside`: the
    same sample, an ``s`` per voxel; a 6-PSS rod of fixed length, which the first test never passes);
    an undecided cube is split
    in eight, and an undecided half decided voxel by voxel as the dense kernel does: the same voxels
    as the dense kernel."""
    n_chains = k0.shape[0]
    nx, ny, nz = xs.shape[0], ys.shape[0], zs.shape[0]
    ncz = (nz + m - 1) // m
    half = m // 2
    for col in prange(cols.shape[0]):
        x0 = cols[col, 0] * m
        y0 = cols[col, 1] * m
        x1 = min(x0 + m, nx)
        y1 = min(y0 + m, ny)
        gap_lo = np.empty(8)
        gap_hi = np.empty(8)
        start = np.empty(n_chains, np.int64)
        vstart = np.empty((m * m, n_chains), np.int64)
        for c in range(n_chains):
            start[c] = nk[c] // 2
            for v in range(m * m):
                vstart[v, c] = nk[c] // 2
        for cz in range(ncz):
            z0 = cz * m
            z1 = min(z0 + m, nz)
            st = _cube_state(0.5 * (xs[x0] + xs[x1 - 1]), 0.5 * (ys[y0] + ys[y1 - 1]), 0.5 * (zs[z0] + zs[z1 - 1]),
                             0, r, rt, lmin2t, lmax2t, lmin2r, lmax2r, start, k0, nk, l0, nl, s_lo, s_hi, w, base,
                             u_axis, k_u, plat, s_axis, k_s, lmin2, lmax2, centre, out2, in2, kb0, blk_centre,
                             blk_out2, blk_in2, gap_lo, gap_hi)
            if st < 2:
                for ix in range(x0, x1):
                    for iy in range(y0, y1):
                        for iz in range(z0, z1):
                            out[ix, iy, iz] = st == 1
                continue
            for sx in range(x0, x1, half):
                ex = min(sx + half, x1)
                for sy in range(y0, y1, half):
                    ey = min(sy + half, y1)
                    for sz in range(z0, z1, half):
                        ez = min(sz + half, z1)
                        st2 = _cube_state(0.5 * (xs[sx] + xs[ex - 1]), 0.5 * (ys[sy] + ys[ey - 1]),
                                          0.5 * (zs[sz] + zs[ez - 1]), 1, r, rt, lmin2t, lmax2t, lmin2r, lmax2r,
                                          start, k0, nk, l0, nl, s_lo, s_hi, w, base, u_axis, k_u, plat, s_axis,
                                          k_s, lmin2, lmax2, centre, out2, in2, kb0, blk_centre, blk_out2, blk_in2,
                                          gap_lo, gap_hi)
                        for ix in range(sx, ex):
                            for iy in range(sy, ey):
                                v = (ix - x0) * m + (iy - y0)
                                for iz in range(sz, ez):
                                    if st2 < 2:
                                        out[ix, iy, iz] = st2 == 1
                                        continue
                                    ok = True
                                    for c in range(n_chains):
                                        if not _chain_ok(xs[ix], ys[iy], zs[iz], c, vstart[v], k0, nk, l0, nl, s_lo,
                                                         s_hi, w, base, u_axis, k_u, plat, s_axis, k_s, lmin2, lmax2,
                                                         centre, out2, in2, kb0, blk_centre, blk_out2, blk_in2,
                                                         gap_lo, gap_hi, 0.0):
                                            ok = False
                                            break
                                    out[ix, iy, iz] = ok


# --------------------------------------------------------------------------------------------
# Python drivers


def paper_design(mech: Mechanism) -> Design | None:
    """The :class:`Design` whose :func:`kinematics.presets.paper` equals ``mech`` (chains and a zero
    reference), or ``None``: the test that routes a description to the paper's engine."""
    if any(mech.reference) or len(mech.chains) != 3:
        return None
    try:
        chain = mech.chains[0]
        if len(chain.carriage) != 2 or len(chain.legs) != 2:
            return None
        arc, radial = chain.carriage
        leg = chain.legs[0]
        lo, hi = arc.range
        eta_range = "centered" if lo == -hi else "from-zero" if lo == 0.0 else None
        if eta_range is None:
            return None
        design = Design(a=2.0 * leg.platform[1], b=2.0 * leg.base[1], d_s=radial.range[1], r=leg.base[0],
                        l_min=leg.length[0], l_s=leg.length[1] - leg.length[0], eta_s=hi - lo,
                        eta_range=eta_range)  # type: ignore[arg-type]
    except (ParameterError, IndexError, TypeError):
        return None
    built = paper(**design.to_dict())
    return design if built.chains == mech.chains else None


@dataclasses.dataclass
class MechanismWorkspaceResult(WorkspaceResult):
    """A :class:`~kinematics.workspace.WorkspaceResult` of a description: ``design`` is the
    equivalent :class:`Design` when the paper's engine computed it (``engine == "paper"``), else
    ``None``; ``samples`` is the number of carriage samples per chain (the general engine)."""

    mechanism: Mechanism | None = None
    engine: str = "general"
    samples: tuple[int, ...] = ()
    length_step: float = 1.0
    interference_undecided: int = 0


def _check_general(mech: Mechanism, settings: WorkspaceSettings) -> None:
    if settings.diagnostics:
        raise ParameterError("diagnostics", True, "not available for a general mechanism (only the paper preset)")
    if settings.joints != Joints():
        raise ParameterError("joints", settings.joints.to_dict(),
                             "none for a mechanism description: its legs carry their own u_cone/s_cone")


def reach_box_general(tables: KernelTables, z_floor: float) -> tuple[tuple[float, ...], tuple[float, ...]]:
    """The analytical box of the module docstring (``P`` within ``lmax_j + rho_j`` of ``c_j - R u_j``
    for every leg), its bottom raised to ``z_floor``; may be empty (``lo > hi`` on an axis)."""
    reach = np.sqrt(tables.out2)[:, None]
    centre = tables.centre - tables.plat
    lo = np.max(centre - reach, axis=0)
    hi = np.min(centre + reach, axis=0)
    lo[2] = max(lo[2], z_floor)
    return tuple(float(x) for x in lo), tuple(float(x) for x in hi)


def _grid_for(tables: KernelTables, settings: WorkspaceSettings) -> GridSpec:
    h = settings.voxel
    if settings.bounds is not None:
        return GridSpec.from_bounds(settings.bounds[0], settings.bounds[1], h)
    lo, hi = reach_box_general(tables, settings.z_floor)
    if any(a > b for a, b in zip(lo, hi)):  # nothing reachable: one voxel at the floor
        lo, hi = (0.0, 0.0, settings.z_floor), (h, h, settings.z_floor + h)
    # snapped outward to multiples of h and grown by a voxel (the bottom stays at the floor):
    # the outermost layer lies beyond the reach, so the box never clips the workspace
    glo = [h * math.floor(lo[a] / h + 1e-9) - h for a in range(2)]
    ghi = [h * math.ceil(hi[a] / h - 1e-9) + h for a in range(2)]
    zlo = h * math.floor(lo[2] / h + 1e-9)
    if zlo < settings.z_floor <= lo[2] + 1e-9:
        zlo = float(settings.z_floor)
    elif zlo > settings.z_floor:
        zlo = max(zlo - h, settings.z_floor)
    zhi = h * math.ceil(hi[2] / h - 1e-9) + h
    return GridSpec.from_bounds((glo[0], glo[1], zlo), (ghi[0], ghi[1], max(zhi, zlo + h)), h)


def general_plan(mech: Mechanism, settings: WorkspaceSettings = WorkspaceSettings(),
                 length_step: float = 1.0) -> tuple[GridSpec, tuple[int, ...]]:
    """The grid the general engine lays for ``mech`` and each chain's number of carriage samples
    (computed before running, for size limits)."""
    _check_general(mech, settings)
    rot = platform_rotation(mech, settings.orientation)
    tables = kernel_tables(mech, rot, settings.eta_step, check_length_step(length_step))
    return _grid_for(tables, settings), tuple(len(t.q) for t in tables.chains)


def compute_general_workspace(mech: Mechanism, settings: WorkspaceSettings = WorkspaceSettings(),
                              length_step: float = 1.0, progress: ProgressFn | None = None,
                              cancel: CancelToken = None) -> MechanismWorkspaceResult:
    """The general engine on any description (never routed; see :func:`compute_mechanism_workspace`).

    ``settings.method``: ``"dense"`` tests every voxel; ``"blocks"`` (default) decides cubes of
    :data:`CUBE`^3 voxels whole where a certificate at the cube's centre holds for all of them
    (:func:`_blocks_kernel`) and tests the others voxel by voxel: the same voxels.
    """
    _check_general(mech, settings)
    length_step = check_length_step(length_step)
    rep = Reporter(progress)
    t0 = time.perf_counter()
    rot = platform_rotation(mech, settings.orientation)
    tables = kernel_tables(mech, rot, settings.eta_step, length_step)
    grid = _grid_for(tables, settings)
    xs, ys, zs = grid.axes()
    nx, ny, nz = grid.shape
    out = np.zeros(grid.shape, np.bool_)
    sub = rep.sub(0.0, 0.5 if settings.bracket else 1.0)  # the bracket reports the second half
    if settings.method == "blocks":
        m = CUBE
        r = math.sqrt(3.0) * 0.5 * np.array([m - 1, m // 2 - 1], float) * grid.h  # levels: edge m, m/2
        lmin = np.sqrt(tables.lmin2)[None, :]
        lmax = np.sqrt(tables.lmax2)[None, :]
        eps = _BOUND_EPS * (1.0 + float(lmax.max()) + float(np.abs(tables.base).max(initial=0.0)))
        rt = r + eps
        lmin2t = np.ascontiguousarray((lmin + rt[:, None]) ** 2)
        lmax2t = np.ascontiguousarray(np.where(lmax - rt[:, None] > 0.0, (lmax - rt[:, None]) ** 2, -1.0))
        lmin2r = np.ascontiguousarray(np.where(lmin - rt[:, None] > 0.0, lmin - rt[:, None], 0.0) ** 2)
        lmax2r = np.ascontiguousarray((lmax + rt[:, None]) ** 2)
        gx, gy = np.meshgrid(np.arange(-(-nx // m)), np.arange(-(-ny // m)), indexing="ij")
        cols = np.ascontiguousarray(np.stack([gx.ravel(), gy.ravel()], axis=1).astype(np.int64))
        step = max(16, int(65536 // max(nz * m * m, 1)))
        for s in range(0, len(cols), step):
            check(cancel)
            with KERNEL_LOCK:
                _blocks_kernel(cols[s:s + step], m, xs, ys, zs, r, rt, lmin2t, lmax2t, lmin2r, lmax2r, *tables.args(),
                               out)
            frac = min(1.0, (s + step) / len(cols))
            sub(frac, f"computing the workspace, {100 * frac:.0f} %")
    else:
        gx, gy = np.meshgrid(np.arange(nx), np.arange(ny), indexing="ij")
        ix, iy = gx.ravel().astype(np.int64), gy.ravel().astype(np.int64)
        step = max(64, int(65536 // max(nz, 1)))
        for s in range(0, ix.size, step):
            check(cancel)
            with KERNEL_LOCK:
                _columns_kernel(ix[s:s + step], iy[s:s + step], xs, ys, zs, *tables.args(), out)
            frac = min(1.0, (s + step) / ix.size)
            sub(frac, f"computing the workspace, {100 * frac:.0f} %")
    undecided = 0
    if any(leg.diameter > 0.0 for _, _, leg in mech.legs):  # leg interference: kinematics/mechanism_interference
        from .mechanism_interference import interference_filter

        if settings.bracket:
            raise ParameterError("bracket", True, NO_BRACKET_DIAMETERS)
        idx = np.argwhere(out)
        pts = np.stack([xs[idx[:, 0]], ys[idx[:, 1]], zs[idx[:, 2]]], axis=1)
        sub(1.0, f"leg interference at {len(pts):,} reachable voxels")
        free, undecided = interference_filter(mech, pts, settings.orientation, settings.eta_step, length_step,
                                              cancel)
        out[tuple(idx[~free].T)] = False
    seconds = time.perf_counter() - t0
    res = MechanismWorkspaceResult(
        design=None, settings=settings, grid=grid, occupancy=out, chain_mask=None,  # type: ignore[arg-type]
        compute_seconds=seconds, n_eta=int(max(len(t.q) for t in tables.chains)), mechanism=mech,
        engine="general", samples=tuple(len(t.q) for t in tables.chains), length_step=length_step,
        interference_undecided=undecided)
    if settings.bracket:
        t1 = time.perf_counter()
        br = general_bracket(mech, tables, grid, settings.eta_step, length_step, settings.z_floor,
                             settings.bracket_refine, rep.sub(0.5, 1.0), cancel)
        res.volume_inner, res.volume_outer = br.volume_inner, br.volume_outer
        res.bracket_seconds = time.perf_counter() - t1
    rep(1.0, "voxels computed")
    return res


def compute_mechanism_workspace(mech: Mechanism, settings: WorkspaceSettings = WorkspaceSettings(),
                                length_step: float = 1.0, progress: ProgressFn | None = None,
                                cancel: CancelToken = None) -> MechanismWorkspaceResult:
    """The constant-orientation position workspace of ``mech`` (module docstring): the paper's engine
    for the paper's mechanism (:func:`paper_design`), the general engine otherwise.

    ``settings`` are :class:`~kinematics.workspace.WorkspaceSettings` (``eta_step`` spaces every
    revolute joint's samples); ``length_step`` spaces a sampled (second) prismatic joint's values.
    """
    design = paper_design(mech)
    if design is None:
        return compute_general_workspace(mech, settings, length_step, progress, cancel)
    res = compute_workspace(design, settings, progress, cancel)
    fields = {f.name: getattr(res, f.name) for f in dataclasses.fields(WorkspaceResult)}
    return MechanismWorkspaceResult(**fields, mechanism=mech, engine="paper", samples=(res.n_eta,) * 3,
                                    length_step=check_length_step(length_step))


def reachable_general(mech: Mechanism, points: np.ndarray,
                      orientation: Sequence[float] | np.ndarray = (0.0, 0.0, 0.0),
                      eta_step: float = 0.5, length_step: float = 1.0) -> np.ndarray:
    """The general engine's test at arbitrary points ``(N, 3)`` (bool ``(N,)``), never routed."""
    _check_general(mech, WorkspaceSettings())
    pts = np.ascontiguousarray(np.asarray(points, float).reshape(-1, 3))
    tables = kernel_tables(mech, platform_rotation(mech, orientation), eta_step, check_length_step(length_step))
    out = np.zeros(len(pts), np.bool_)
    if len(pts):
        with KERNEL_LOCK:
            _points_kernel(pts, *tables.args(), out)
    if len(pts) and any(leg.diameter > 0.0 for _, _, leg in mech.legs):
        from .mechanism_interference import interference_filter

        live = np.flatnonzero(out)
        out[live] = interference_filter(mech, pts[live], orientation, eta_step, length_step)[0]
    return out


_WARM = False


def warm_up_general() -> float:
    """Compile (or load from numba's disk cache) the general engine's kernels; returns the seconds it
    took (so that ``compute_seconds`` never counts the load)."""
    global _WARM
    t0 = time.perf_counter()
    if not _WARM:
        from .presets import six_pups

        mech = six_pups()
        box = ((-80, -80, 80), (80, 80, 200))
        compute_general_workspace(mech, WorkspaceSettings(voxel=40.0, bounds=box))
        compute_general_workspace(mech, WorkspaceSettings(voxel=40.0, bounds=box, method="dense", bracket=True))
        reachable_general(mech, np.array([[0.0, 0.0, 150.0]]))
        _WARM = True
    return time.perf_counter() - t0


# --------------------------------------------------------------------------------------------
# inverse kinematics with redundancy resolution


@dataclasses.dataclass
class ChainIK:
    """One chain's carriage values (degrees for a revolute joint), the leg lengths there, the
    smallest length margin ``min_j min(l_j - lmin_j, lmax_j - l_j)`` and whether it is feasible."""

    chain: int
    q: list[float]
    lengths: list[float]
    margin: float
    feasible: bool

    def to_dict(self) -> dict:
        return dataclasses.asdict(self)


def _margins(tab: ChainTables, lo: np.ndarray, hi: np.ndarray, plat: np.ndarray, p: np.ndarray,
             s: np.ndarray) -> np.ndarray:
    """Length margins (K, S) at samples ``K`` of the chain and exact-joint values ``s`` (S,) or (K, S)."""
    v0 = (p + plat)[None, :, :] - tab.base                                # (K, n, 3)
    pj = np.einsum("knc,kc->kn", v0, tab.w)                              # (K, n)
    qj = np.maximum(np.einsum("knc,knc->kn", v0, v0) - pj ** 2, 0.0)
    s = np.broadcast_to(s, (tab.base.shape[0], s.shape[-1]))
    length = np.sqrt((s[:, None, :] - pj[:, :, None]) ** 2 + qj[:, :, None])  # (K, n, S)
    return np.minimum(length - lo[None, :, None], hi[None, :, None] - length).min(axis=1)


def mechanism_ik(mech: Mechanism, position: Sequence[float] | np.ndarray,
                 orientation: Sequence[float] | np.ndarray = (0.0, 0.0, 0.0),
                 eta_step: float = 0.5, length_step: float = 1.0, s_samples: int = 401) -> list[ChainIK]:
    """Redundancy resolution of a description: per chain the carriage values that keep its legs
    furthest inside their length ranges (maximise the smallest margin).

    The chain's non-exact joints take the engine's samples (``eta_step``, ``length_step``); the
    exact joint ``s`` is searched on ``s_samples`` values over its stroke, then refined by two
    zoom-ins of the same size around the best value (the margin is 1-Lipschitz in ``s``, so the
    result is within ``stroke / (s_samples - 1)^3`` of the best over ``s`` at that sample). Cones
    are not part of the margin.
    """
    rot = platform_rotation(mech, orientation)
    p = np.asarray(position, float)
    out = []
    for c, chain in enumerate(mech.chains):
        tab = chain_tables(chain, eta_step, check_length_step(length_step))
        plat = np.array([leg.platform for leg in chain.legs], float) @ rot.T
        lo = np.array([leg.length[0] for leg in chain.legs])
        hi = np.array([leg.length[1] for leg in chain.legs])
        s_lo, s_hi = tab.s_range
        n = s_samples if s_hi > s_lo else 1
        s = np.linspace(s_lo, s_hi, n)
        marg = _margins(tab, lo, hi, plat, p, s)
        k, i = (int(x) for x in np.unravel_index(int(np.argmax(marg)), marg.shape))
        best_s, best_m = float(s[i]), float(marg[k, i])
        width = (s_hi - s_lo) / max(n - 1, 1)
        one = ChainTables(tab.q[k:k + 1], tab.base[k:k + 1], tab.w[k:k + 1], tab.rot[k:k + 1], tab.exact, tab.s_range)
        for _ in range(2 if n > 1 else 0):
            s = np.linspace(max(s_lo, best_s - width), min(s_hi, best_s + width), n)
            m = _margins(one, lo, hi, plat, p, s)[0]
            i = int(np.argmax(m))
            if m[i] > best_m:
                best_s, best_m = float(s[i]), float(m[i])
            width = 2.0 * width / (n - 1)
        q = [float(x) for x in tab.q[k]]
        if tab.exact is not None:
            q[tab.exact] = best_s
        base = tab.base[k] + best_s * tab.w[k]
        lengths = np.linalg.norm(p + plat - base, axis=1)
        out.append(ChainIK(c, q, [float(x) for x in lengths], best_m, best_m >= -1e-9))
    return out


# --------------------------------------------------------------------------------------------
# the certified bracket
#
# A certified bracket of a general mechanism's continuous workspace volume:
# ``volume_inner <= V <= volume_outer`` (the proof of :mod:`kinematics.bracket` extended to any carriage).
#
# ``V`` is the volume of the continuous workspace ``W``: every platform position (at the fixed
# orientation, above ``z_floor``) for which every chain has SOME carriage values anywhere in its box,
# not only at the samples. Each voxel is a closed cube of edge ``h`` with half-diagonal
# ``delta = sqrt(3) h / 2`` about its centre ``Pc``, classified per chain:
#
# * **inside**: some carriage sample admits an ``s`` (the exact joint, (G1)-(G2) of
#   :mod:`kinematics.mechanism_workspace`) with every leg in ``[lmin + delta + eps, lmax - delta - eps]``
#   at ``Pc``: leg lengths are 1-Lipschitz in the position, so the same carriage values serve every
#   point of the cube.
# * **inside, a chain of one leg** (:func:`_single_leg_inside`; a 6-PSS rod of fixed length, where the
#   test above never passes: ``lmin = lmax`` leaves no margin): at a sample, the exact joint moves the
#   leg's base joint along a line, ``D(s) = D_k + s w`` with ``s`` in ``[s_lo, s_hi]``, so the leg's
#   length ``f(s) = |B - D(s)| = sqrt((p - s)^2 + q)`` (``p = (B - D_k) . w``, ``q`` the squared distance
#   of ``B`` from the line) takes every value of ``[m, M]``, ``m = min f`` (the distance of ``B`` from the
#   segment), ``M = max f`` (at an end), by continuity. ``m`` and ``M`` are 1-Lipschitz in the position
#   (a minimum and a maximum of 1-Lipschitz functions), so when ``[m + delta + eps, M - delta - eps]``
#   at ``Pc`` meets ``[lmin, lmax]``, every point ``P`` of the cube has ``[m(P), M(P)]`` containing that
#   meet: some ``s`` (depending on ``P``) puts the leg in its range, at this same sample.
# * **outside**: no sample admits an ``s`` with the legs in ``[lmin - e, lmax + e]``, ``e = delta +
#   e_c + eps``, or the chain's balls grown by ``e`` reject ``Pc``. ``e_c`` bounds how far a base
#   joint moves between a carriage value and the nearest sample: the sum over the chain's sampled
#   joints of half their spacing times their lever, where a sampled prismatic joint's lever is 1 and a
#   revolute joint's is ``L_m = max_j |D0_j| + sum of max(|lo|, |hi|) over the prismatic joints after
#   it`` (in the frame after the joints before ``m`` the base joint is the rest of the chain applied to
#   ``D0_j``: rotations about that frame's origin keep norms, translations add at most their stroke),
#   in radians. Proof: if a point ``P`` of the cube were served by carriage values ``q``, the nearest
#   sample ``q_k`` (the same ``s``) puts every base joint within ``e_c`` of where ``q`` puts it, and
#   ``|P - Pc| <= delta``, so every leg length at ``(Pc, q_k, s)`` is within ``e`` of its length at
#   ``(P, q, s)``: sample ``k`` would pass the relaxed test. The balls contain every base joint of the
#   samples, so those of the continuous box lie within ``e_c`` of them.
#
# A cube is inside ``W`` when every chain is inside, outside when some chain is outside, else a
# boundary cube; ``N_in h^3 <= V <= (N_in + N_boundary) h^3`` provided ``W`` lies in the grid, which
# is checked: the grid is grown by ``ceil(max e_c / h) + 1`` voxels (never below the floor) and every
# cube of its outer layer (but the floor) must be outside, else ``volume_outer`` is ``inf``.
# Refinement: a boundary cube is cut into its 8 half cubes, each classified by the same two tests
# with its own half-diagonal (the proof above holds for any cube), ``refine`` times; inside half cubes
# add to ``N_in h^3``, outside ones leave, the last boundary ones make the outer bound. Joint
# cones are refused (their axes turn with the revolute joints: not part of this proof yet).


@dataclasses.dataclass(frozen=True)
class GeneralBracket:
    """``volume_inner <= V <= volume_outer`` and the cube counts (``outer`` is ``inf`` when ``W`` may
    leave the grid)."""

    volume_inner: float
    volume_outer: float
    inside: int
    boundary: int
    grid: GridSpec
    boundary_left: int = 0  # boundary cubes of the last refinement level (``boundary`` without one)


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


@njit(cache=True)
def _single_leg_inside(px, py, pz, c, k0, nk, l0, s_lo, s_hi, w, base, plat, lmin2, lmax2, shift):
    """The one-leg inside test of the comment above: some sample ``k`` of chain ``c`` (one leg, ``j``)
    has ``[m + shift, M - shift]`` meeting ``[lmin, lmax]`` at ``P``, where ``[m, M]`` is the range of
    the leg's length as the exact joint runs over ``[s_lo, s_hi]``."""
    j = l0[c]
    lmin, lmax = math.sqrt(lmin2[j]), math.sqrt(lmax2[j])
    lo, hi = s_lo[c], s_hi[c]
    for kk in range(nk[c]):
        k = k0[c] + kk
        vx = px + plat[j, 0] - base[k, j, 0]
        vy = py + plat[j, 1] - base[k, j, 1]
        vz = pz + plat[j, 2] - base[k, j, 2]
        p = vx * w[k, 0] + vy * w[k, 1] + vz * w[k, 2]
        q = max(vx * vx + vy * vy + vz * vz - p * p, 0.0)
        near = 0.0 if lo <= p <= hi else min(abs(p - lo), abs(p - hi))
        far = max(abs(p - lo), abs(p - hi))
        if max(math.sqrt(q + near * near) + shift, lmin) <= min(math.sqrt(q + far * far) - shift, lmax):
            return True
    return False


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
                                            blk_centre, blk_out2, blk_in2, gap_lo, gap_hi, delta_t) \
                        and not (nl[c] == 1 and _single_leg_inside(xs[ix], ys[iy], zs[iz], c, k0, nk, l0, s_lo, s_hi,
                                                                   w, base, plat, lmin2, lmax2, delta_t)):
                    st = 2
            state[ix, iy, iz] = st


@njit(parallel=True, cache=True, nogil=True)
def _bracket_points_kernel(pts, delta_t, e_out, lmin2t, lmax2t, lmin2r, lmax2r, k0, nk, l0, nl, s_lo, s_hi, w,
                           base, u_axis, k_u, plat, s_axis, k_s, lmin2, lmax2, centre, out2, in2, kb0, blk_centre,
                           blk_out2, blk_in2, state):
    """:func:`_bracket_kernel` at cube centres ``pts`` (N, 3) (the refinement's half cubes)."""
    n_chains = k0.shape[0]
    for i in prange(pts.shape[0]):
        gap_lo = np.empty(8)
        gap_hi = np.empty(8)
        start = np.empty(n_chains, np.int64)
        for c in range(n_chains):
            start[c] = nk[c] // 2
        st = 1
        for c in range(n_chains):
            if _chain_out(pts[i, 0], pts[i, 1], pts[i, 2], e_out[c], e_out[c], c, k0, nk, l0, nl, s_lo, s_hi, w,
                          base, u_axis, k_u, plat, s_axis, k_s, lmin2r[c], lmax2r[c], centre, out2, in2, kb0,
                          blk_centre, blk_out2, blk_in2, gap_lo, gap_hi):
                st = 0
                break
            if st == 1 and not _chain_ok(pts[i, 0], pts[i, 1], pts[i, 2], c, start, k0, nk, l0, nl, s_lo, s_hi, w,
                                        base, u_axis, k_u, plat, s_axis, k_s, lmin2t, lmax2t, centre, out2, in2,
                                        kb0, blk_centre, blk_out2, blk_in2, gap_lo, gap_hi, delta_t) \
                    and not (nl[c] == 1 and _single_leg_inside(pts[i, 0], pts[i, 1], pts[i, 2], c, k0, nk, l0, s_lo,
                                                               s_hi, w, base, plat, lmin2, lmax2, delta_t)):
                st = 2
        state[i] = st


def _bracket_thresholds(delta: float, slack: np.ndarray, tables: KernelTables, legs_chain: np.ndarray,
                        eps: float) -> tuple:
    """The tightened and relaxed squared limits of cubes of half-diagonal ``delta`` (the comment above)."""
    lmin = np.sqrt(tables.lmin2)
    lmax = np.sqrt(tables.lmax2)
    delta_t = delta + eps
    lmin2t = (lmin + delta_t) ** 2
    lmax2t = np.where(lmax - delta_t > 0.0, (lmax - delta_t) ** 2, -1.0)
    e_out = delta + slack + eps                                   # per chain
    e_leg = e_out[legs_chain]
    lmin2r = np.where(lmin - e_leg > 0.0, lmin - e_leg, 0.0) ** 2
    lmax2r = (lmax + e_leg) ** 2
    # per chain rows: the kernel reads row c (the legs of other chains are never read); writable copies
    # (a broadcast view stays read-only for one chain, and numba would compile the kernel once more)
    n = len(slack)
    return (delta_t, e_out, lmin2t, lmax2t, np.repeat(lmin2r[None], n, axis=0), np.repeat(lmax2r[None], n, axis=0))


#: Voxels of the bracket's grid per launch of its cube pass, and half cubes per launch of its
#: refinement: each launch holds :data:`~kinematics.parallel.KERNEL_LOCK` for a fraction of a second,
#: and the cancel token is checked between launches.
BRACKET_VOXELS_PER_CALL = 1 << 18
BRACKET_CUBES_PER_CALL = 1 << 16


def general_bracket(mech: Mechanism, tables: KernelTables, grid: GridSpec, eta_step: float, length_step: float,
                    z_floor: float, refine: int = 0, progress: ProgressFn | None = None,
                    cancel: CancelToken = None) -> GeneralBracket:
    """The bracket of the module docstring around the workspace computed on ``grid``; ``refine``
    halvings of the boundary cubes (each child cube classified by the same tests with its own
    half-diagonal, the same proof: ``volume_inner`` grows and ``volume_outer`` shrinks).

    Work and memory are bounded per step: the cube pass runs in slabs of about
    :data:`BRACKET_VOXELS_PER_CALL` voxels, and the refinement depth first, :data:`BRACKET_CUBES_PER_CALL`
    half cubes at a time (a level's boundary children are refined before the next chunk of its
    parents is cut, so at most ``refine`` chunks are held at once, where a level at a time would hold
    ``8^refine`` children of every boundary cube). Each launch holds ``KERNEL_LOCK`` on its own; the
    cancel token is checked between them (raises :class:`~kinematics.progress.Cancelled`). The counts
    are summed per level and turned into volumes in the order of a level at a time, so the bracket
    does not depend on the chunk sizes (tested)."""
    if any(leg.u_cone is not None or leg.s_cone is not None for _, _, leg in mech.legs):
        raise ParameterError("bracket", True, NO_BRACKET_CONES)
    rep = Reporter(progress)
    h = grid.h
    slack = np.array([chain_slack(c, eta_step, length_step) for c in mech.chains])
    pad = int(math.ceil(float(slack.max(initial=0.0)) / h)) + 1
    lo = (grid.lo[0] - pad * h, grid.lo[1] - pad * h, max(z_floor, grid.lo[2] - pad * h))
    hi = (grid.hi[0] + pad * h, grid.hi[1] + pad * h, grid.hi[2] + pad * h)
    big = GridSpec.from_bounds(lo, hi, h)
    xs, ys, zs = big.axes()
    lmax = np.sqrt(tables.lmax2)
    eps = _BOUND_EPS * (1.0 + float(lmax.max()) + float(np.abs(tables.base).max(initial=0.0)))
    legs_chain = np.array([c for c, _, _ in mech.legs])
    state = np.zeros(big.shape, np.uint8)
    cube_args = (*_bracket_thresholds(math.sqrt(3.0) * 0.5 * h, slack, tables, legs_chain, eps), *tables.args())
    nx, ny, nz = big.shape
    slab = max(1, BRACKET_VOXELS_PER_CALL // max(ny * nz, 1))
    stage = rep.sub(0.0, 0.5 if refine > 0 else 1.0)
    for a in range(0, nx, slab):
        stage(a / nx, f"certified bracket: classifying the cubes, {100 * a / nx:.0f} %")
        check(cancel)
        with KERNEL_LOCK:
            _bracket_kernel(xs[a:a + slab], ys, zs, *cube_args, state[a:a + slab])
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
    idx = np.argwhere(state == 2)
    del state, rim
    centres = np.stack([xs[idx[:, 0]], ys[idx[:, 1]], zs[idx[:, 2]]], axis=1) if len(idx) else np.zeros((0, 3))
    # per level: the half cubes found inside and those left on the boundary (the next level's parents)
    found = [0] * refine
    kept = [0] * refine
    level_args = [(*_bracket_thresholds(math.sqrt(3.0) * 0.25 * h / 2 ** k, slack, tables, legs_chain, eps),
                   *tables.args()) for k in range(refine)]
    offsets = np.array([[i, j, k] for i in (-1, 1) for j in (-1, 1) for k in (-1, 1)], float)
    per = max(1, BRACKET_CUBES_PER_CALL // 8)  # parents per launch
    refining = rep.sub(0.5, 1.0)

    def split(parents: np.ndarray, level: int, span: tuple[float, float]) -> None:
        """Classify the 8 half cubes of each boundary cube of edge ``h / 2^level`` in ``parents`` and
        refine the boundary ones further (depth first); ``span``: the share of the refinement this call
        covers (for the progress, reported at every launch)."""
        quarter = 0.25 * h / 2 ** level  # a child's centre is a quarter of the parent's edge off its centre
        n = len(parents)
        for s in range(0, n, per):
            done = span[0] + (span[1] - span[0]) * s / n
            refining(done, f"certified bracket: refining {len(centres):,} boundary cubes, {100 * done:.0f} %")
            check(cancel)
            kids = np.ascontiguousarray((parents[s:s + per, None, :] + quarter * offsets[None]).reshape(-1, 3))
            st = np.zeros(len(kids), np.uint8)
            with KERNEL_LOCK:
                _bracket_points_kernel(kids, *level_args[level], st)
            found[level] += int(np.count_nonzero(st == 1))
            rest = kids[st == 2]
            kept[level] += len(rest)
            if level + 1 < refine:
                split(rest, level + 1, (done, span[0] + (span[1] - span[0]) * min(s + per, n) / n))

    if refine > 0 and len(centres):
        split(centres, 0, (0.0, 1.0))
    v_in = inside * vv
    edge = h
    n_par = len(centres)
    for k in range(refine):  # the sums of a level at a time
        if not n_par:
            break
        edge *= 0.5
        v_in += found[k] * edge ** 3
        n_par = kept[k]
    v_out = v_in + n_par * edge ** 3
    return GeneralBracket(v_in, v_out if contained else math.inf, inside, boundary, big, n_par)


def bracket_unavailable(mech: Mechanism) -> str | None:
    """Why :func:`general_bracket` does not apply to ``mech`` (the sentence after "certified
    bracket"), or ``None`` when it does."""
    if any(leg.u_cone is not None or leg.s_cone is not None for _, _, leg in mech.legs):
        return NO_BRACKET_CONES
    if any(leg.diameter > 0.0 for _, _, leg in mech.legs):
        return NO_BRACKET_DIAMETERS
    return None


def bracket_caveat(mech: Mechanism) -> str | None:
    """What the bracket of ``mech`` cannot show, or ``None``: in a chain of several legs, a leg of
    fixed length (``l_min = l_max``) makes the length test with the limits tightened by a cube's
    half-diagonal fail everywhere, and the one-leg test (:func:`_single_leg_inside`) does not apply, so
    no cube is inside and the inner bound stays 0 at every refinement."""
    if any(len(chain.legs) > 1 and any(leg.length[1] - leg.length[0] <= 0.0 for leg in chain.legs)
           for chain in mech.chains):
        return ("inner bound 0 by construction: a leg of fixed length (l_min = l_max) in a chain of several legs "
                "leaves no margin for the inside test")
    return None


def general_bracket_of(result: MechanismWorkspaceResult, refine: int | None = None,
                       progress: ProgressFn | None = None, cancel: CancelToken = None) -> VolumeBracket:
    """:func:`general_bracket` around a computed general workspace (its grid, orientation, samples
    and floor; ``refine``: default the settings' ``bracket_refine``), as the paper path's
    :class:`~kinematics.bracket.VolumeBracket` (``cubes_inside``, ``cubes_boundary``: the bracket's
    grid, which is the workspace's grown by the arc slack).

    Raises:
        ParameterError: on ``bracket`` where :func:`bracket_unavailable` gives a reason.
    """
    mech = result.mechanism
    assert mech is not None, "a general mechanism's result"
    why = bracket_unavailable(mech)
    if why is not None:
        raise ParameterError("bracket", True, why)
    s = result.settings
    r = s.bracket_refine if refine is None else int(refine)
    tables = kernel_tables(mech, platform_rotation(mech, s.orientation), s.eta_step, result.length_step)
    br = general_bracket(mech, tables, result.grid, s.eta_step, result.length_step, s.z_floor, r, progress, cancel)
    return VolumeBracket(volume_inner=br.volume_inner, volume_outer=br.volume_outer, cubes_inside=br.inside,
                         cubes_boundary=br.boundary, voxel=result.grid.h, refine=r, boundary_left=br.boundary_left)
