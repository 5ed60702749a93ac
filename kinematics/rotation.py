"""Platform orientation: the Euler-angle rotation of eq. (2), its rate map (eq. (7)), and the
Euler-Rodrigues rotation about ``y'`` of eq. (27) -- both of the latter corrected.

Angles are in degrees in the public functions ending in ``_deg`` and in radians otherwise.

Corrections to the paper (derived here, checked by the tests):

* eq. (7): for ``R1 = Rz(psi) Ry(theta) Rx(phi)`` the angular velocity is
  ``omega = R2 [phi', theta', psi']^T`` with
  ``R2 = [[c(theta)c(psi), -s(psi), 0], [c(theta)s(psi), c(psi), 0], [-s(theta), 0, 1]]``;
  the paper prints ``phi`` where ``psi`` belongs.
* eq. (27): the Euler-Rodrigues matrix is ``R' = c I + (1 - c) n n^T + s [n]_x``; the paper's
  diagonal writes ``s_x`` for ``n_x`` and the (1,3) and (2,3) entries carry the wrong sign of the
  ``s(tau)`` term (its matrix is not orthogonal).
"""

from __future__ import annotations

import numpy as np

#: The ``y'`` symmetry axis of Sec. III: in the base plane, 60 deg from ``x``.
Y_PRIME_AXIS = np.array([0.5, np.sqrt(3.0) / 2.0, 0.0])


def rot_x(angle: float) -> np.ndarray:
    """Rotation about x by ``angle`` radians."""
    c, s = np.cos(angle), np.sin(angle)
    return np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]])


def rot_y(angle: float) -> np.ndarray:
    """Rotation about y by ``angle`` radians."""
    c, s = np.cos(angle), np.sin(angle)
    return np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])


def rot_z(angle: float) -> np.ndarray:
    """Rotation about z by ``angle`` radians."""
    c, s = np.cos(angle), np.sin(angle)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def euler_zyx(psi: float, theta: float, phi: float) -> np.ndarray:
    """Paper eq. (2): ``R1 = Rz(psi) Ry(theta) Rx(phi)`` (radians)."""
    return rot_z(psi) @ rot_y(theta) @ rot_x(phi)


def euler_zyx_deg(psi: float, theta: float, phi: float) -> np.ndarray:
    """Paper eq. (2) with angles in degrees."""
    return euler_zyx(np.radians(psi), np.radians(theta), np.radians(phi))


def euler_rate_matrix(psi: float, theta: float) -> np.ndarray:
    """Corrected eq. (7): ``omega = R2 @ [phi', theta', psi']`` for ``R1 = Rz Ry Rx`` (radians)."""
    cp, sp = np.cos(psi), np.sin(psi)
    ct, st = np.cos(theta), np.sin(theta)
    return np.array([[ct * cp, -sp, 0.0], [ct * sp, cp, 0.0], [-st, 0.0, 1.0]])


def axis_angle(axis: np.ndarray, angle: float) -> np.ndarray:
    """Corrected eq. (27), Euler-Rodrigues: rotation by ``angle`` radians about unit ``axis``."""
    n = np.asarray(axis, dtype=float)
    n = n / np.linalg.norm(n)
    c, s = np.cos(angle), np.sin(angle)
    k = np.array([[0.0, -n[2], n[1]], [n[2], 0.0, -n[0]], [-n[1], n[0], 0.0]])
    return c * np.eye(3) + (1.0 - c) * np.outer(n, n) + s * k


def euler_zyx_from_matrix(rot: np.ndarray) -> tuple[float, float, float]:
    """Inverse of :func:`euler_zyx`: ``(psi, theta, phi)`` in radians, ``theta in [-pi/2, pi/2]``."""
    rot = np.asarray(rot, dtype=float)
    theta = float(np.arcsin(np.clip(-rot[2, 0], -1.0, 1.0)))
    psi = float(np.arctan2(rot[1, 0], rot[0, 0]))
    phi = float(np.arctan2(rot[2, 1], rot[2, 2]))
    return psi, theta, phi
