"""Forward kinematics: the platform pose from the 12 actuator values, by Newton's method on the six
leg-length equations (eq. (15)) with the analytic Jacobian ``J_x`` (eq. (25)) -- the carriages fix
the U-joint positions, so only the six lengths constrain the pose.

A parallel mechanism has several assembly modes; Newton converges to the one nearest the initial
guess (by default the platform centred above the base at a height estimated from the lengths).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence

import numpy as np

from .design import Design, ParameterError
from .geometry import base_points, platform_points_local
from .jacobian import jacobians
from .pose import Pose
from .rotation import euler_zyx


@dataclasses.dataclass
class ForwardResult:
    """Outcome of :func:`forward_kinematics` with its convergence report."""

    pose: Pose
    converged: bool
    iterations: int
    residual: float  # max |l(pose) - l_target|
    message: str

    def to_dict(self) -> dict:
        return {"pose": self.pose.to_dict(), "converged": self.converged, "iterations": self.iterations,
                "residual": self.residual, "message": self.message}


def _lengths(design: Design, v: np.ndarray, D: np.ndarray) -> np.ndarray:
    rot = euler_zyx(v[5], v[4], v[3])  # v = [x, y, z, phi, theta, psi]
    B = v[:3] + platform_points_local(design) @ rot.T
    return np.linalg.norm(B - D, axis=-1).reshape(6)


def _to_pose(v: np.ndarray) -> Pose:
    return Pose(v[0], v[1], v[2], float(np.degrees(v[5])), float(np.degrees(v[4])), float(np.degrees(v[3])))


def forward_kinematics(design: Design, lengths: Sequence[float], d: Sequence[float], eta_deg: Sequence[float],
                       initial: Pose | None = None, tol: float = 1e-10, max_iter: int = 50) -> ForwardResult:
    """Forward kinematics: Newton solve of ``l_i^j(pose) = lengths`` for the pose (module docstring).

    Parameters
    ----------
    design : Design
        The mechanism's dimensions.
    lengths : sequence of 6 floats or array_like, shape (3, 2)
        Leg lengths ordered ``l_1^1, l_1^2, ..., l_3^2``.
    d : sequence of 3 floats
        Linear carriage positions.
    eta_deg : sequence of 3 floats
        Arc carriage positions, degrees.
    initial : Pose, optional
        Starting pose (default: centred, height from the mean length).
    tol : float, optional
        Largest leg-length residual accepted as converged.
    max_iter : int, optional
        Newton iterations at most.

    Returns
    -------
    ForwardResult
        The pose, whether it converged, the iterations, the residual and a message.

    Raises
    ------
    ParameterError
        Not six positive finite lengths.

    Examples
    --------
    >>> import paraspace as ps
    >>> design, d, eta = ps.Design(), [30.0] * 3, [0.0] * 3
    >>> ik = ps.inverse_kinematics(design, ps.Pose(0.0, 0.0, 130.0), d, eta)
    >>> fk = ps.forward_kinematics(design, ik.lengths, d, eta)
    >>> fk.converged, round(fk.pose.z, 6)
    (True, 130.0)
    """
    target = np.asarray(lengths, float).reshape(-1)
    if target.size != 6 or not np.all(np.isfinite(target)) or np.any(target <= 0):
        raise ParameterError("lengths", list(target), "six positive leg lengths")
    D = base_points(design, d, eta_deg)
    if initial is None:
        horiz = abs(design.r - float(np.mean(d)) - design.a)
        z0 = float(np.sqrt(max(np.mean(target) ** 2 - horiz ** 2, 1.0)))
        initial = Pose(0.0, 0.0, z0)
    v = np.array([initial.x, initial.y, initial.z, np.radians(initial.phi), np.radians(initial.theta),
                  np.radians(initial.psi)])
    res = _lengths(design, v, D) - target
    it = 0
    for it in range(1, max_iter + 1):
        if np.max(np.abs(res)) < tol:
            it -= 1
            break
        Jx = jacobians(design, _to_pose(v), d, eta_deg).J_x
        try:
            step = np.linalg.solve(Jx, -res)
        except np.linalg.LinAlgError:
            return ForwardResult(_to_pose(v), False, it, float(np.max(np.abs(res))), "singular Jacobian J_x")
        alpha = 1.0
        norm0 = np.linalg.norm(res)
        while alpha > 1e-4:  # backtracking keeps the iteration from jumping assembly modes
            v_new = v + alpha * step
            res_new = _lengths(design, v_new, D) - target
            if np.linalg.norm(res_new) < norm0:
                break
            alpha *= 0.5
        v, res = v_new, res_new
        if abs(v[4]) >= np.pi / 2:
            return ForwardResult(_to_pose(np.clip(v, -1e4, 1e4)), False, it, float(np.max(np.abs(res))),
                                 "left the Euler-angle chart (|theta| >= 90 deg)")
    r = float(np.max(np.abs(res)))
    ok = r < tol * 10
    return ForwardResult(_to_pose(v), ok, it, r, "converged" if ok else f"not converged after {max_iter} iterations")
