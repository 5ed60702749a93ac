"""Slow, plain-numpy reference for the reachability test, written independently of the compiled
kernel (:mod:`kinematics.feasibility`): used by the tests (voxel-by-voxel agreement) and by the
benchmark (as the baseline the engine is compared against).

For each arc sample ``eta_k`` (the same samples as the engine) and each chain, it builds the
candidate radial positions ``rho`` -- the rail ends, every root of ``|B_j - D_j(rho)| = l_min`` and
``= l_max`` (a quadratic in ``rho``), and the midpoints between consecutive candidates -- and
accepts the chain if at one candidate both legs' actual lengths, computed from the joint
positions, lie within the limits. Between consecutive candidates no constraint changes sign,
so testing candidates and midpoints is exact in ``rho``.
"""

from __future__ import annotations

import numpy as np

from .design import Design
from .feasibility import default_n_eta
from .geometry import GAMMA, LEG_SIGN, platform_points_local
from .rotation import euler_zyx_deg

TOL = 1e-9


def _chain_ok_at_eta(design: Design, B: np.ndarray, varpi: float) -> np.ndarray:
    """B: (N, 2, 3) platform points of one chain. Returns bool (N,)."""
    e = np.array([np.cos(varpi), np.sin(varpi), 0.0])
    t = np.array([-np.sin(varpi), np.cos(varpi), 0.0])
    rho_lo, rho_hi = design.rho_limits
    n = B.shape[0]
    cands = [np.full(n, rho_lo), np.full(n, rho_hi)]
    for j in range(2):
        w = B[:, j] - LEG_SIGN[j] * design.b / 2.0 * t
        bq = -2.0 * (w @ e)
        for L in (design.l_min, design.l_max):
            cq = np.einsum("ij,ij->i", w, w) - L * L
            disc = bq * bq - 4.0 * cq
            sq = np.sqrt(np.where(disc >= 0, disc, np.nan))
            cands += [(-bq - sq) / 2.0, (-bq + sq) / 2.0]
    C = np.column_stack(cands)
    C = np.where(np.isfinite(C), np.clip(C, rho_lo, rho_hi), rho_lo)
    C.sort(axis=1)
    C = np.concatenate([C, 0.5 * (C[:, 1:] + C[:, :-1])], axis=1)  # (N, K)
    ok = np.ones(C.shape, bool)
    for j in range(2):
        D = C[..., None] * e + LEG_SIGN[j] * design.b / 2.0 * t  # (N, K, 3)
        length = np.linalg.norm(B[:, None, j, :] - D, axis=-1)
        ok &= (length >= design.l_min - TOL) & (length <= design.l_max + TOL)
    return np.asarray(ok.any(axis=1))


def reference_reachable(design: Design, points: np.ndarray, orientation=(0.0, 0.0, 0.0),
                        eta_step: float = 0.5, chunk: int = 100_000) -> np.ndarray:
    """Reachability of each point (N, 3) at orientation ``(psi, theta, phi)`` deg, brute force."""
    pts = np.asarray(points, float).reshape(-1, 3)
    rot = euler_zyx_deg(*orientation)
    u = platform_points_local(design) @ rot.T  # (3, 2, 3)
    n_eta = default_n_eta(design, eta_step)
    lo, hi = design.eta_limits
    etas = np.radians(np.linspace(lo, hi, n_eta)) if n_eta > 1 else np.radians([lo])
    out = np.ones(pts.shape[0], bool)
    for s in range(0, pts.shape[0], chunk):
        P = pts[s:s + chunk]
        alive = np.ones(P.shape[0], bool)
        for i in range(3):
            B = P[:, None, :] + u[i][None, :, :]
            found = np.zeros(P.shape[0], bool)
            for eta in etas:
                todo = alive & ~found
                if not todo.any():
                    break
                found[todo] = _chain_ok_at_eta(design, B[todo], GAMMA[i] + eta)
            alive &= found
        out[s:s + chunk] = alive
    return out


def gough_stewart_reachable(design: Design, points: np.ndarray, orientation=(0.0, 0.0, 0.0)) -> np.ndarray:
    """Direct 6-UPS check for ``d_s = eta_s = 0``: the six U joints are fixed at ``rho = r``,
    ``eta = 0`` (or the range's only value) and a pose is reachable iff all six lengths are within limits."""
    pts = np.asarray(points, float).reshape(-1, 3)
    rot = euler_zyx_deg(*orientation)
    u = (platform_points_local(design) @ rot.T).reshape(6, 3)
    eta0 = np.radians(design.eta_limits[0])
    D = []
    for i in range(3):
        w = GAMMA[i] + eta0
        for j in range(2):
            lat = LEG_SIGN[j] * design.b / 2.0
            D.append([design.r * np.cos(w) - lat * np.sin(w), design.r * np.sin(w) + lat * np.cos(w), 0.0])
    L = np.linalg.norm(pts[:, None, :] + u[None] - np.array(D)[None], axis=-1)
    return np.all((L >= design.l_min) & (L <= design.l_max), axis=1)
