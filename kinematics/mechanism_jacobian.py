"""Jacobians of any :class:`~kinematics.mechanism.Mechanism`: the paper's eqs. (21)-(26) for a
general carriage.

**Definition.** With ``x = [P, Theta]``, ``Theta = [phi, theta, psi]`` (radians, ``R = Rot(reference)
Rz(psi) Ry(theta) Rx(phi)``) and ``q = [l_1 .. l_6, carriage joints chain by chain]`` (revolute values
in radians here, although the user-facing unit is degrees), the velocity relation is

    J_x xdot = J_q qdot                                                                  (21)

* Row ``j`` of ``J_x``: ``s_j^T [I_3, -[u_j]_x R_ref R2]`` with ``s_j`` the unit vector from ``D_j`` to
  ``B_j``, ``u_j = R u_bar_j`` and ``R2`` the corrected rate matrix of eq. (7)
  (:func:`kinematics.rotation.euler_rate_matrix`): ``omega = R_ref R2 Theta_dot``.
* ``J_q = [I_6 | C]`` with ``C[j, m] = s_j^T dD_j/dq_m`` for a joint ``m`` of leg ``j``'s own chain
  (zero otherwise), where with ``(A, a) = T_1 ... T_{m-1}`` (M1) the joints before ``m``:

      prismatic along u_m:           dD_j/dq_m = A u_m ,
      revolute about n_m (radians):  dD_j/dq_m = (A n_m) x (D_j - a) .

  (``s_j^T (B_j - D_j)`` is ``l_j``, so ``ldot_j = s_j^T (Bdot_j - Ddot_j)``, which is (21).)
* ``J_h = [J_x[:, :3], J_x[:, 3:] / L]`` with ``L`` the mean distance of the platform joints from the
  platform origin (the paper's ``a/2`` takes the platform radius's half; here the radius, stated),
  ``J = J_h^{-1} J_q`` and its condition number ``sigma_max / sigma_min``.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence

import numpy as np

from .mechanism import Mechanism, _axis_rotation
from .mechanism_workspace import platform_rotation
from .rotation import euler_rate_matrix, euler_zyx_deg


@dataclasses.dataclass
class MechanismJacobians:
    """``J_x`` (6, 6), ``J_q`` (6, 6 + carriage joints), ``J_h``, ``J`` and the condition number of ``J``."""

    J_x: np.ndarray
    J_q: np.ndarray
    J_h: np.ndarray
    J: np.ndarray
    condition_number: float

    def to_dict(self) -> dict:
        return {k: (v.tolist() if isinstance(v, np.ndarray) else v) for k, v in dataclasses.asdict(self).items()}


def carriage_derivatives(mech: Mechanism, q: Sequence[Sequence[float]]) -> tuple[np.ndarray, np.ndarray]:
    """The legs' base joints ``D_j`` (6, 3) and ``dD_j/dq_m`` (6, M, 3) for every carriage joint ``m``
    (chain by chain; revolute joints per radian), zero where ``m`` is not on leg ``j``'s chain."""
    n_joints = sum(len(c.carriage) for c in mech.chains)
    legs = mech.legs
    d_pts = mech.base_points(q)
    deriv = np.zeros((len(legs), n_joints, 3))
    m0 = 0
    for c, (chain, qc) in enumerate(zip(mech.chains, q)):
        rows = [i for i, (cc, _, _) in enumerate(legs) if cc == c]
        rot, trans = np.eye(3), np.zeros(3)
        for m, (joint, value) in enumerate(zip(chain.carriage, qc)):
            axis = np.asarray(joint.axis, float)
            if joint.type == "prismatic":
                deriv[rows, m0 + m] = rot @ axis
                trans = trans + rot @ (float(value) * axis)
            else:
                deriv[rows, m0 + m] = np.cross(rot @ axis, d_pts[rows] - trans)
                rot = rot @ _axis_rotation(axis, np.radians(float(value)))
        m0 += len(chain.carriage)
    return d_pts, deriv


def mechanism_jacobians(mech: Mechanism, position: Sequence[float] | np.ndarray, orientation: Sequence[float],
                        q: Sequence[Sequence[float]]) -> MechanismJacobians:
    """The Jacobians of the module docstring at platform pose ``(position, orientation)``
    (``orientation`` = ``(psi, theta, phi)`` degrees) and carriage values ``q`` (per chain, degrees for
    a revolute joint)."""
    psi, theta, phi = (float(v) for v in orientation)
    rot = platform_rotation(mech, (psi, theta, phi))
    ref = euler_zyx_deg(*mech.reference)
    u = np.array([leg.platform for _, _, leg in mech.legs], float) @ rot.T
    b_pts = np.asarray(position, float) + u
    d_pts, deriv = carriage_derivatives(mech, q)
    v = b_pts - d_pts
    s = v / np.linalg.norm(v, axis=1, keepdims=True)
    r2 = ref @ euler_rate_matrix(np.radians(psi), np.radians(theta))
    j_x = np.zeros((len(u), 6))
    for j in range(len(u)):
        j_x[j, :3] = s[j]
        j_x[j, 3:] = -s[j] @ (_skew(u[j]) @ r2)
    c_mat = np.einsum("jc,jmc->jm", s, deriv)
    j_q = np.concatenate([np.eye(len(u)), c_mat], axis=1)
    radius = float(np.mean(np.linalg.norm([leg.platform for _, _, leg in mech.legs], axis=1))) or 1.0
    j_h = np.concatenate([j_x[:, :3], j_x[:, 3:] / radius], axis=1)
    try:
        jac = np.linalg.solve(j_h, j_q)
        sv = np.linalg.svd(jac, compute_uv=False)
        cond = float(sv[0] / sv[-1]) if sv[-1] > 0 else float("inf")
    except np.linalg.LinAlgError:
        jac = np.full_like(j_q, np.nan)
        cond = float("inf")
    return MechanismJacobians(j_x, j_q, j_h, jac, cond)


def _skew(v: np.ndarray) -> np.ndarray:
    return np.array([[0.0, -v[2], v[1]], [v[2], 0.0, -v[0]], [-v[1], v[0], 0.0]])
