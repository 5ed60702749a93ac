"""Dexterity of any :class:`~kinematics.mechanism.Mechanism`: the local conditioning ``1/kappa`` as a
field over a computed workspace, its GCI and the well-conditioned workspace (the quantities of
:mod:`kinematics.dexterity` for a description).

**Definition.** At the centre ``P`` of every reachable voxel of a workspace computed at the constant
orientation ``(psi, theta, phi)``, with ``q*(P)`` the carriage values of the redundancy resolution
(:func:`kinematics.mechanism_workspace.mechanism_ik`: per chain the values of largest smallest length
margin) and ``J = J_h^{-1} J_q`` of :mod:`kinematics.mechanism_jacobian` ((21), ``J_h`` homogenised
by the mean platform-joint radius ``L``)

    1/kappa(P) = sigma_min(J(P, R, q*(P))) / sigma_max(J(P, R, q*(P)))      (0 where J_h is singular)   (X1)
    GCI = mean of (X1) over the reachable voxels,  well conditioned: 1/kappa >= kappa_min.            (X2)

Only the resolved carriage (``mode="resolved"``) is computed for a general mechanism (``"best"`` is
refused by name). The paper's mechanism (a result computed by the paper's engine,
``engine == "paper"``) is routed to :func:`kinematics.dexterity.dexterity_field`: the paper path's
numbers exactly (its ``L = a/2`` and its compiled resolver).

Cost: the field is computed in batches of voxels: the resolver's search of
:func:`~kinematics.mechanism_workspace.mechanism_ik` (per chain ``K x 401`` margins over the carriage
samples and the exact joint, then two zooms of 401 about the best) vectorised over the batch
(:func:`resolved_carriages`, the same search: tested equal to ``mechanism_ik`` per voxel), then the
Jacobians of (21) for the whole batch (:func:`inverse_condition_batch`, tested equal to
:func:`~kinematics.mechanism_jacobian.mechanism_jacobians` per voxel) and a batched solve and SVD.
"""

from __future__ import annotations

import math
import time
from collections.abc import Sequence

import numpy as np

from .design import ParameterError
from .dexterity import DexterityField, check_kappa_min, dexterity_field
from .mechanism import Mechanism
from .mechanism_jacobian import mechanism_jacobians
from .mechanism_workspace import (
    MechanismWorkspaceResult,
    chain_tables,
    check_length_step,
    mechanism_ik,
    platform_rotation,
)
from .progress import CancelToken, ProgressFn, Reporter, check
from .rotation import euler_rate_matrix, euler_zyx_deg

#: Margin evaluations (batch x carriage samples x legs x exact-joint values) per resolver step.
BATCH_WORK = 4_000_000
#: Values of the exact joint in each step of the search (``mechanism_ik``'s ``s_samples``).
S_SAMPLES = 401


def _margins_batch(base: np.ndarray, w: np.ndarray, plat: np.ndarray, pts: np.ndarray, s: np.ndarray,
                   lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
    """``min_j min(l_j - lo_j, hi_j - l_j)`` by (G2), ``(N, K, S)``: points ``(N, 3)``, base joints at ``s = 0``
    ``(K, n, 3)`` (or per point ``(N, 1, n, 3)``) with the exact joint's direction ``(K, 3)`` (``(N, 1, 3)``)
    and its values ``s`` ``(S,)`` (``(N, 1, S)``)."""
    v0 = pts[:, None, None, :] + plat - base                                             # (N, K, n, 3)
    pj = np.einsum("...nc,...c->...n", v0, w)
    qj = np.maximum(np.einsum("...nc,...nc->...n", v0, v0) - pj ** 2, 0.0)
    length = np.sqrt((s[..., None, :] - pj[..., None]) ** 2 + qj[..., None])            # (N, ..., n, S)
    return np.minimum(length - lo[:, None], hi[:, None] - length).min(axis=-2)


def resolved_carriages(mech: Mechanism, pts: np.ndarray, orientation: Sequence[float], eta_step: float = 0.5,
                       length_step: float = 1.0) -> list[np.ndarray]:
    """:func:`~kinematics.mechanism_workspace.mechanism_ik`'s carriage values (per chain ``(N, k)``,
    degrees for a revolute joint) at every point of ``pts`` ``(N, 3)``: the same search, vectorised."""
    rot = platform_rotation(mech, orientation)
    pts = np.asarray(pts, float).reshape(-1, 3)
    out = []
    for chain in mech.chains:
        tab = chain_tables(chain, eta_step, check_length_step(length_step))
        plat = np.array([leg.platform for leg in chain.legs], float) @ rot.T
        lo = np.array([leg.length[0] for leg in chain.legs])
        hi = np.array([leg.length[1] for leg in chain.legs])
        s_lo, s_hi = tab.s_range
        n = S_SAMPLES if s_hi > s_lo else 1
        s = np.linspace(s_lo, s_hi, n)
        n_k = tab.base.shape[0]
        chunk = max(1, BATCH_WORK // max(n_k * len(chain.legs) * n, 1))
        parts = []
        for c0 in range(0, len(pts), chunk):
            p = pts[c0:c0 + chunk]
            marg = _margins_batch(tab.base, tab.w, plat, p, s, lo, hi).reshape(len(p), -1)     # (N, K S)
            flat = np.argmax(marg, axis=1)
            k, i = flat // n, flat % n
            best_s, best_m = s[i], marg[np.arange(len(p)), flat]
            width = np.full(len(p), (s_hi - s_lo) / max(n - 1, 1))
            base_k, w_k = tab.base[k], tab.w[k]                                                # (N, n, 3), (N, 3)
            for _ in range(2 if n > 1 else 0):
                zs = np.linspace(np.maximum(s_lo, best_s - width), np.minimum(s_hi, best_s + width), n, axis=1)
                m = _margins_batch(base_k[:, None], w_k[:, None], plat, p, zs[:, None], lo, hi)[:, 0]  # (N, S)
                j = np.argmax(m, axis=1)
                better = m[np.arange(len(p)), j] > best_m
                best_s = np.where(better, zs[np.arange(len(p)), j], best_s)
                best_m = np.where(better, m[np.arange(len(p)), j], best_m)
                width = 2.0 * width / (n - 1)
            qk = tab.q[k].astype(float)
            if tab.exact is not None:
                qk[:, tab.exact] = best_s
            parts.append(qk)
        out.append(np.concatenate(parts, axis=0) if parts else np.zeros((0, tab.q.shape[1])))
    return out


def _rodrigues_batch(axis: np.ndarray, angle_rad: np.ndarray) -> np.ndarray:
    kx = np.array([[0.0, -axis[2], axis[1]], [axis[2], 0.0, -axis[0]], [-axis[1], axis[0], 0.0]])
    return (np.eye(3)[None] + np.sin(angle_rad)[:, None, None] * kx[None]
            + (1.0 - np.cos(angle_rad))[:, None, None] * (kx @ kx)[None])


def _carriage_derivatives_batch(mech: Mechanism, q: list[np.ndarray]) -> tuple[np.ndarray, np.ndarray]:
    """:func:`~kinematics.mechanism_jacobian.carriage_derivatives` for ``N`` carriage values at once:
    ``D`` ``(N, 6, 3)`` and ``dD/dq`` ``(N, 6, M, 3)`` (revolute joints per radian)."""
    n_pts = q[0].shape[0] if q else 0
    n_joints = sum(len(c.carriage) for c in mech.chains)
    d_pts = np.zeros((n_pts, len(mech.legs), 3))
    deriv = np.zeros((n_pts, len(mech.legs), n_joints, 3))
    row, m0 = 0, 0
    for chain, qc in zip(mech.chains, q):
        rows = slice(row, row + len(chain.legs))
        legs = np.array([leg.base for leg in chain.legs], float)
        steps = []
        rot = np.broadcast_to(np.eye(3), (n_pts, 3, 3)).copy()
        trans = np.zeros((n_pts, 3))
        for m, joint in enumerate(chain.carriage):  # (M1): the transforms before each joint, then the last
            axis = np.asarray(joint.axis, float)
            steps.append((rot, trans))
            if joint.type == "prismatic":
                trans = trans + (rot @ axis) * qc[:, m, None]
            else:
                rot = rot @ _rodrigues_batch(axis, np.radians(qc[:, m]))
        d_pts[:, rows] = np.einsum("lc,ndc->nld", legs, rot) + trans[:, None, :]
        for m, (joint, (r_m, t_m)) in enumerate(zip(chain.carriage, steps)):
            a = r_m @ np.asarray(joint.axis, float)                                             # (N, 3)
            if joint.type == "prismatic":
                deriv[:, rows, m0 + m] = a[:, None, :]
            else:
                deriv[:, rows, m0 + m] = np.cross(a[:, None, :], d_pts[:, rows] - t_m[:, None, :])
        row += len(chain.legs)
        m0 += len(chain.carriage)
    return d_pts, deriv


def inverse_condition_batch(mech: Mechanism, pts: np.ndarray, orientation: Sequence[float],
                            q: list[np.ndarray]) -> np.ndarray:
    """(X1) at points ``(N, 3)`` with carriage values ``q`` (per chain ``(N, k)``): the Jacobians of
    :func:`~kinematics.mechanism_jacobian.mechanism_jacobians` for all points at once."""
    psi, theta, phi = (float(v) for v in orientation)
    rot = platform_rotation(mech, (psi, theta, phi))
    ref = euler_zyx_deg(*mech.reference)
    plat = np.array([leg.platform for _, _, leg in mech.legs], float)
    u = plat @ rot.T
    pts = np.asarray(pts, float).reshape(-1, 3)
    d_pts, deriv = _carriage_derivatives_batch(mech, q)
    v = pts[:, None, :] + u[None] - d_pts
    s = v / np.linalg.norm(v, axis=2, keepdims=True)
    r2 = ref @ euler_rate_matrix(np.radians(psi), np.radians(theta))
    radius = float(np.mean(np.linalg.norm(plat, axis=1))) or 1.0
    j_h = np.concatenate([s, (np.cross(u[None], s) @ r2) / radius], axis=2)                   # (N, 6, 6)
    j_q = np.concatenate([np.broadcast_to(np.eye(6), (len(pts), 6, 6)),
                          np.einsum("njc,njmc->njm", s, deriv)], axis=2)
    out = np.zeros(len(pts))
    for i0 in range(0, len(pts), 4096):
        jh, jq = j_h[i0:i0 + 4096], j_q[i0:i0 + 4096]
        try:
            jac = np.linalg.solve(jh, jq)
        except np.linalg.LinAlgError:  # a singular J_h in the batch: one by one (0 where singular)
            out[i0:i0 + len(jh)] = [_one_inverse_condition(a, b) for a, b in zip(jh, jq)]
            continue
        sv = np.linalg.svd(jac, compute_uv=False)
        out[i0:i0 + len(jh)] = np.where(sv[:, 0] > 0, sv[:, -1] / np.where(sv[:, 0] > 0, sv[:, 0], 1.0), 0.0)
    return out


def _one_inverse_condition(j_h: np.ndarray, j_q: np.ndarray) -> float:
    try:
        sv = np.linalg.svd(np.linalg.solve(j_h, j_q), compute_uv=False)
    except np.linalg.LinAlgError:
        return 0.0
    return float(sv[-1] / sv[0]) if sv[0] > 0 else 0.0


def inverse_condition_at(mech: Mechanism, position: Sequence[float] | np.ndarray, orientation: Sequence[float],
                         eta_step: float = 0.5, length_step: float = 1.0) -> float:
    """(X1) at one position: ``1/kappa`` at the resolved carriage (0 where ``J_h`` is singular)."""
    chains = mechanism_ik(mech, position, orientation, eta_step, length_step)
    cond = mechanism_jacobians(mech, position, orientation, [c.q for c in chains]).condition_number
    return 0.0 if not math.isfinite(cond) or cond <= 0.0 else 1.0 / cond


def check_general_mode(mode: str) -> str:
    """The dexterity mode of a general mechanism: only ``"resolved"`` (the message names the field)."""
    if mode != "resolved":
        raise ParameterError("dexterity_mode", mode, "'resolved' for a general mechanism ('best' only for the "
                             "paper's mechanism)")
    return mode


def mechanism_dexterity_field(result: MechanismWorkspaceResult, kappa_min: float = 0.1, mode: str = "resolved",
                              progress: ProgressFn | None = None, cancel: CancelToken = None, *,
                              search: str | None = None, margin_tolerance: float | None = None) -> DexterityField:
    """(X1)-(X2) over the reachable voxels of ``result`` (a workspace of a description, at its
    orientation); the paper's engine's results run :func:`kinematics.dexterity.dexterity_field`
    (``search`` and ``margin_tolerance``: its carriage search, when given). A general description's
    field runs its resolver's search at every voxel: a ``search`` other than ``"full"`` is refused."""
    if result.engine == "paper":
        extra: dict = {} if search is None else {"search": search}
        if margin_tolerance is not None:
            extra["margin_tolerance"] = margin_tolerance
        return dexterity_field(result, kappa_min, mode, progress=progress, cancel=cancel, **extra)
    if search is not None and search != "full":
        raise ParameterError("dexterity_search", search, "full (a general description's dexterity runs its "
                                                         "resolver's search at every voxel)")
    check_general_mode(mode)
    kappa_min = check_kappa_min(kappa_min)
    mech = result.mechanism
    if mech is None:
        raise ParameterError("result", "workspace", "a workspace of a mechanism description")
    rep = Reporter(progress)
    t0 = time.perf_counter()
    occ = np.asarray(result.occupancy, bool)
    pts = result.grid.points()[occ]
    orientation = tuple(float(v) for v in result.settings.orientation)
    vals = np.zeros(pts.shape[0])
    step = 2048
    for i in range(0, pts.shape[0], step):
        check(cancel)
        rep(i / max(pts.shape[0], 1), "dexterity")
        p = pts[i:i + step]
        q = resolved_carriages(mech, p, orientation, result.settings.eta_step, result.length_step)
        vals[i:i + step] = inverse_condition_batch(mech, p, orientation, q)
    field = np.full(occ.shape, np.nan)
    field[occ] = vals
    well = np.zeros(occ.shape, bool)
    well[occ] = vals >= kappa_min
    vv = result.grid.voxel_volume
    n = vals.size
    rep(1.0, "done")
    return DexterityField(
        inverse_condition=field, gci=float(vals.mean()) if n else float("nan"), kappa_min=kappa_min,
        well_conditioned=well, well_conditioned_volume=float(well.sum()) * vv, volume=n * vv, mode=mode,
        seconds=time.perf_counter() - t0, minimum=float(vals.min()) if n else float("nan"),
        maximum=float(vals.max()) if n else float("nan"))
