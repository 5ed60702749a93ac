"""Inverse kinematics: leg lengths ``l_i^j = |B_i^j - D_i^j|`` (paper eq. (15)) for a pose and
carriage values, and the state of each leg against its limits."""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from .design import Design, ParameterError
from .geometry import base_points, platform_points
from .pose import Pose

LEG_STATES: tuple[str, ...] = ("inside", "at_limit", "too_short", "too_long")


def leg_lengths(design: Design, pose: Pose, d: ArrayLike, eta_deg: ArrayLike) -> np.ndarray:
    """Eq. (15): the six leg lengths, shape (3, 2), for a pose and carriage values ``d_i``, ``eta_i`` (deg)."""
    b = platform_points(design, pose.position, pose.rotation)
    dd = base_points(design, np.asarray(d, float), np.asarray(eta_deg, float))
    return np.linalg.norm(b - dd, axis=-1)


def limit_tolerance(design: Design) -> float:
    """Band inside the limits in which a leg counts as "at a limit": 1 % of the leg stroke (min 1e-9)."""
    return max(1e-9, 0.01 * design.l_s)


def leg_margin(design: Design, lengths: np.ndarray) -> np.ndarray:
    """Signed distance of each length to its nearer limit: ``min(l - l_min, l_max - l)`` (negative outside)."""
    lengths = np.asarray(lengths, float)
    return np.minimum(lengths - design.l_min, design.l_max - lengths)


def leg_states(design: Design, lengths: np.ndarray) -> list[list[str]]:
    """Per leg: ``"too_short"`` (l < l_min), ``"too_long"`` (l > l_max), ``"at_limit"`` (within
    :func:`limit_tolerance` of a limit) or ``"inside"``."""
    lengths = np.asarray(lengths, float).reshape(3, 2)
    tol = limit_tolerance(design)
    out: list[list[str]] = []
    for i in range(3):
        row = []
        for j in range(2):
            l = lengths[i, j]
            if l < design.l_min - 1e-9:
                row.append("too_short")
            elif l > design.l_max + 1e-9:
                row.append("too_long")
            elif min(l - design.l_min, design.l_max - l) <= tol:
                row.append("at_limit")
            else:
                row.append("inside")
        out.append(row)
    return out


def check_carriage(design: Design, d: ArrayLike, eta_deg: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
    """Validate hand-set carriage values against the strokes; raises :class:`ParameterError` naming
    ``d_1``..``d_3`` / ``eta_1``..``eta_3`` (paper numbering) and the valid range."""
    d = np.asarray(d, float).reshape(-1)
    eta = np.asarray(eta_deg, float).reshape(-1)
    if d.size != 3:
        raise ParameterError("d", list(d), "three values d_1,d_2,d_3")
    if eta.size != 3:
        raise ParameterError("eta", list(eta), "three values eta_1,eta_2,eta_3 (degrees)")
    lo, hi = design.eta_limits
    for i in range(3):
        if not (np.isfinite(d[i]) and -1e-9 <= d[i] <= design.d_s + 1e-9):
            raise ParameterError(f"d_{i + 1}", float(d[i]), f"[0, d_s={design.d_s:g}]")
        if not (np.isfinite(eta[i]) and lo - 1e-9 <= eta[i] <= hi + 1e-9):
            raise ParameterError(f"eta_{i + 1}", float(eta[i]), f"[{lo:g}, {hi:g}] degrees ({design.eta_range})")
    return d, eta
