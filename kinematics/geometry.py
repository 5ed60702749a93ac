"""Joint positions of the mechanism: platform joints ``B_i^j`` (eqs. (3)-(5)) and base U joints
``D_i^j`` (eq. (11)).

Indexing in code is zero-based: chain ``i in {0, 1, 2}`` is the paper's ``i = 1, 2, 3`` and leg
``j in {0, 1}`` is the paper's ``j = 1, 2``; the paper's sign ``(-1)^(j+1)`` is :data:`LEG_SIGN`.
Arrays of leg quantities are ordered ``(i, j)`` row-major, i.e. ``l_1^1, l_1^2, l_2^1, ...`` as the
paper's ``q_1``.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from .design import Design

#: ``gamma_i = (i - 1) 2 pi / 3`` in radians (eq. (5)).
GAMMA = np.array([0.0, 2.0 * np.pi / 3.0, 4.0 * np.pi / 3.0])
#: The paper's ``(-1)^(j+1)`` for ``j = 1, 2``.
LEG_SIGN = np.array([1.0, -1.0])


def platform_points_local(design: Design) -> np.ndarray:
    """Eq. (4): ``u_bar_i^j = Z_i [sqrt(3) a/2, (-1)^(j+1) a/2, 0]^T`` in the platform frame, shape (3, 2, 3).

    The six points lie on the circle of radius ``a`` at ``gamma_i -+ 30`` degrees.
    """
    a = design.a
    out = np.empty((3, 2, 3))
    for i in range(3):
        c, s = np.cos(GAMMA[i]), np.sin(GAMMA[i])
        for j in range(2):
            px, py = np.sqrt(3.0) * a / 2.0, LEG_SIGN[j] * a / 2.0
            out[i, j] = (c * px - s * py, s * px + c * py, 0.0)
    return out


def platform_points(design: Design, position: np.ndarray, rotation: np.ndarray) -> np.ndarray:
    """Eq. (3): ``B_i^j = P_o + R1 u_bar_i^j`` in the base frame, shape (3, 2, 3)."""
    return np.asarray(position, float) + platform_points_local(design) @ np.asarray(rotation, float).T


def base_points(design: Design, d: ArrayLike, eta_deg: ArrayLike) -> np.ndarray:
    """Eq. (11): ``D_i^j = Z'_i [r - d_i, (-1)^(j+1) b/2, 0]^T`` with ``varpi_i = eta_i + gamma_i``.

    Args:
        d: radial carriage values ``d_i`` (3,), measured inward from ``r``.
        eta_deg: arc carriage values ``eta_i`` in degrees (3,).

    Returns:
        Array (3, 2, 3).
    """
    d = np.asarray(d, float).reshape(3)
    varpi = np.radians(np.asarray(eta_deg, float).reshape(3)) + GAMMA
    out = np.zeros((3, 2, 3))
    for i in range(3):
        c, s = np.cos(varpi[i]), np.sin(varpi[i])
        rho = design.r - d[i]
        for j in range(2):
            lat = LEG_SIGN[j] * design.b / 2.0
            out[i, j, 0] = c * rho - s * lat
            out[i, j, 1] = s * rho + c * lat
    return out


def carriage_rails(design: Design, samples: int = 48) -> dict[str, np.ndarray]:
    """Polylines of the strokes for drawing: per chain the arc at ``rho = r`` and the radial rail.

    Returns ``{"arcs": (3, samples, 3), "radials": (3, 2, 3)}`` where the radial rail of chain ``i``
    runs along its centre direction ``gamma_i`` (at ``eta = 0``) from ``rho = r`` to ``r - d_s``.
    """
    lo, hi = design.eta_limits
    eta = np.radians(np.linspace(lo, hi, samples))
    arcs = np.zeros((3, samples, 3))
    radials = np.zeros((3, 2, 3))
    for i in range(3):
        ang = GAMMA[i] + eta
        arcs[i, :, 0] = design.r * np.cos(ang)
        arcs[i, :, 1] = design.r * np.sin(ang)
        for k, rho in enumerate(design.rho_limits[::-1]):
            radials[i, k, :2] = rho * np.cos(GAMMA[i]), rho * np.sin(GAMMA[i])
    return {"arcs": arcs, "radials": radials}
