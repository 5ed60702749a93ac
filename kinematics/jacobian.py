"""Jacobians of paper eqs. (17)-(26), with the paper's typos corrected.

Velocity relation (eq. (21)): ``J_x xdot = J_q qdot`` with ``x = [P_o, Theta]``,
``Theta = [phi, theta, psi]`` (radians) and ``q = [l_1^1 .. l_3^2, d_1, d_2, d_3, eta_1, eta_2, eta_3]``
(``eta`` in radians here, although the user-facing unit is degrees).

* Row ``(i, j)`` of ``J_x`` (eq. (25)): ``s_i^jT [I_3, -[u_i^j]_x R2]``, with ``s`` the unit vector
  from ``D`` to ``B``, ``u = R1 u_bar`` and ``R2`` the corrected rate matrix of eq. (7)
  (:func:`kinematics.rotation.euler_rate_matrix`).
* ``J_q = [I_6 | E | F]`` (eq. (23)) with ``e_i^j = s_i^jT h_i`` and ``f_i^j = s_i^jT t_i^j``, where
  ``h_i = dD/dd = -(cos varpi_i, sin varpi_i, 0)`` and (corrected eq. (14))

      t_i^j = dD_i^j/deta = ( -(r - d_i) sin varpi_i - (-1)^(j+1) (b/2) cos varpi_i,
                               (r - d_i) cos varpi_i - (-1)^(j+1) (b/2) sin varpi_i,  0 ).

  The paper prints ``(r - d_i) sin varpi_i`` in the second component (it must be ``cos``) and
  writes ``t_i`` without the leg index although it depends on ``j`` through ``b``.
* ``J_h = [J_x[:, :3], J_x[:, 3:] / L]`` with ``L = a/2`` (dimensionally homogeneous, eq. (26)
  text), ``J = J_h^{-1} J_q`` (eq. (26)); its condition number is ``sigma_max / sigma_min``.
"""

from __future__ import annotations

import dataclasses

import numpy as np
from numpy.typing import ArrayLike

from .design import Design
from .geometry import GAMMA, LEG_SIGN, base_points, platform_points, platform_points_local
from .pose import Pose
from .rotation import euler_rate_matrix


def skew(v: np.ndarray) -> np.ndarray:
    """``[v]_x`` such that ``[v]_x w = v x w``."""
    return np.array([[0.0, -v[2], v[1]], [v[2], 0.0, -v[0]], [-v[1], v[0], 0.0]])


@dataclasses.dataclass
class Jacobians:
    """The Jacobians of eqs. (22)-(26) at one configuration."""

    J_x: np.ndarray  # (6, 6)
    J_q: np.ndarray  # (6, 12)
    J_h: np.ndarray  # (6, 6)
    J: np.ndarray  # (6, 12)
    condition_number: float  # of J (inf when J_h is singular)

    def to_dict(self) -> dict:
        return {k: (v.tolist() if isinstance(v, np.ndarray) else v) for k, v in dataclasses.asdict(self).items()}


def jacobians(design: Design, pose: Pose, d: ArrayLike, eta_deg: ArrayLike) -> Jacobians:
    """The Jacobians of eqs. (22)-(26) at one configuration.

    Parameters
    ----------
    design : Design
        The mechanism's dimensions.
    pose : Pose
        Platform position and orientation.
    d : array_like, shape (3,)
        Linear carriage positions.
    eta_deg : array_like, shape (3,)
        Arc carriage positions, degrees.

    Returns
    -------
    Jacobians
        ``J_x`` (6, 6), ``J_q`` (6, 12), ``J_h`` (6, 6), ``J`` (6, 12) and the condition number of
        ``J`` (``inf`` when ``J_h`` is singular).

    Examples
    --------
    >>> import paraspace as ps
    >>> jac = ps.jacobians(ps.Design(), ps.Pose(0.0, 0.0, 130.0), [30.0] * 3, [0.0] * 3)
    >>> jac.J.shape, round(jac.condition_number, 2)
    ((6, 12), 100.85)
    """
    rot = pose.rotation
    B = platform_points(design, pose.position, rot)
    D = base_points(design, d, eta_deg)
    u = platform_points_local(design) @ rot.T
    R2 = euler_rate_matrix(np.radians(pose.psi), np.radians(pose.theta))
    varpi = np.radians(np.asarray(eta_deg, float)) + GAMMA
    d = np.asarray(d, float)
    J_x = np.zeros((6, 6))
    J_q = np.zeros((6, 12))
    J_q[:, :6] = np.eye(6)
    for i in range(3):
        c, s = np.cos(varpi[i]), np.sin(varpi[i])
        h = np.array([-c, -s, 0.0])
        rho = design.r - d[i]
        for j in range(2):
            row = 2 * i + j
            vec = B[i, j] - D[i, j]
            sv = vec / np.linalg.norm(vec)
            J_x[row, :3] = sv
            J_x[row, 3:] = -sv @ skew(u[i, j]) @ R2
            lat = LEG_SIGN[j] * design.b / 2.0
            t = np.array([-rho * s - lat * c, rho * c - lat * s, 0.0])
            J_q[row, 6 + i] = sv @ h
            J_q[row, 9 + i] = sv @ t
    L = design.characteristic_length
    J_h = np.hstack([J_x[:, :3], J_x[:, 3:] / L])
    try:
        J = np.linalg.solve(J_h, J_q)
        sv = np.linalg.svd(J, compute_uv=False)
        cond = float(sv[0] / sv[-1]) if sv[-1] > 0 else float("inf")
    except np.linalg.LinAlgError:
        J = np.full((6, 12), np.nan)
        cond = float("inf")
    return Jacobians(J_x=J_x, J_q=J_q, J_h=J_h, J=J, condition_number=cond)
