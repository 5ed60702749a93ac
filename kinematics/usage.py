"""Actuator-usage maps over a whole workspace: how much of each stroke, and of each joint's cone, the
redundancy resolution's carriage pose uses at every reachable voxel (our documented definition).

At a voxel centre ``P`` (the result's orientation ``R``) each chain ``i`` takes the carriage pose of
largest margin ``min_j min(l_j - l_min, l_max - l_j)`` over an ``n_eta x n_rho`` grid of its strokes
(both ends included; the redundancy resolution of :mod:`kinematics.redundancy` on a coarser grid and
without its zoom-ins, so that a whole workspace costs seconds). There

* ``stroke_use`` = the largest over the chains of ``|d - d_s/2| / (d_s/2)`` and ``|eta - eta_mid| /
  (eta_s/2)``: 0 with every carriage at mid-stroke, 1 with one at a stroke end;
* ``leg_use`` = the largest over the six legs of ``|l - l_mid| / (l_s/2)`` (``l_mid = (l_min +
  l_max)/2``): 1 with a leg at a limit (above 1 at the few surface voxels whose feasible carriage
  poses all fall between the grid's);
* ``joint_angle`` = the largest angle between a leg and its U or S mount axis (degrees,
  :func:`kinematics.joints.cone_angles`' definition with the joint options' ``cone_axis``, also when
  no cone is set), the tightest joint a designer must size.

Unreachable voxels get NaN. :func:`usage_summary` adds histograms (for the explorer's Plots tab).
"""

from __future__ import annotations

import dataclasses
from typing import Any

import numpy as np

from .geometry import GAMMA, LEG_SIGN, platform_points_local
from .joints import Joints, cone_table
from .progress import CancelToken, check
from .rotation import euler_zyx_deg

__all__ = ["UsageMaps", "actuator_usage", "usage_summary"]


@dataclasses.dataclass
class UsageMaps:
    """Per voxel of the result's grid (NaN where unreachable): ``stroke_use``, ``leg_use`` (0-1) and
    ``joint_angle`` (degrees); ``d``, ``eta`` (3, grid shape) the chosen carriage values."""

    stroke_use: np.ndarray
    leg_use: np.ndarray
    joint_angle: np.ndarray
    d: np.ndarray
    eta: np.ndarray


def actuator_usage(result: Any, n_eta: int = 25, n_rho: int = 21, chunk: int = 4096,
                   cancel: CancelToken = None) -> UsageMaps:
    """The maps of the module docstring for a computed ``WorkspaceResult`` (its orientation, joints)."""
    design = result.design
    joints: Joints = result.settings.joints
    rot = euler_zyx_deg(*result.settings.orientation)
    occ = np.asarray(result.occupancy, bool)
    pts = result.grid.points()[occ]
    lo, hi = design.eta_limits
    etas = np.linspace(lo, hi, n_eta) if hi > lo else np.array([lo])
    r_lo, r_hi = design.rho_limits
    rhos = np.linspace(r_lo, r_hi, n_rho) if r_hi > r_lo else np.array([r_lo])
    u = platform_points_local(design) @ rot.T  # (3, 2, 3)
    jc = cone_table(design, joints, rot)
    n = pts.shape[0]
    d_out = np.full((3, n), np.nan)
    e_out = np.full((3, n), np.nan)
    leg_use = np.zeros(n)
    stroke_use = np.zeros(n)
    angle = np.zeros(n)
    half_l = 0.5 * design.l_s
    l_mid = design.l_min + half_l
    eta_mid, half_eta = 0.5 * (lo + hi), 0.5 * (hi - lo)
    half_d = 0.5 * design.d_s
    zaxis = np.array([0.0, 0.0, 1.0])
    for s in range(0, n, chunk):
        check(cancel)
        P = pts[s:s + chunk]
        for i in range(3):
            varpi = GAMMA[i] + np.radians(etas)
            c, sn = np.cos(varpi)[:, None], np.sin(varpi)[:, None]  # (E, 1)
            margin = np.full((P.shape[0], etas.size, rhos.size), np.inf)
            for j in range(2):
                B = P + u[i, j]
                lat = LEG_SIGN[j] * design.b / 2.0
                dx = c * rhos[None, :] - sn * lat  # (E, R)
                dy = sn * rhos[None, :] + c * lat
                bx, by, bz = (B[:, k, None, None] for k in range(3))
                L = np.sqrt((bx - dx) ** 2 + (by - dy) ** 2 + bz ** 2)
                margin = np.minimum(margin, np.minimum(L - design.l_min, design.l_max - L))
            best = margin.reshape(P.shape[0], -1).argmax(axis=1)
            ke, kr = np.unravel_index(best, (etas.size, rhos.size))
            eta, rho = etas[ke], rhos[kr]
            d = design.r - rho
            d_out[i, s:s + chunk], e_out[i, s:s + chunk] = d, eta
            if half_d > 0:
                stroke_use[s:s + chunk] = np.maximum(stroke_use[s:s + chunk], np.abs(d - half_d) / half_d)
            if half_eta > 0:
                stroke_use[s:s + chunk] = np.maximum(stroke_use[s:s + chunk], np.abs(eta - eta_mid) / half_eta)
            vp = GAMMA[i] + np.radians(eta)
            e = np.stack([np.cos(vp), np.sin(vp), np.zeros_like(vp)], axis=1)
            t = np.stack([-np.sin(vp), np.cos(vp), np.zeros_like(vp)], axis=1)
            for j in range(2):
                D = rho[:, None] * e + (LEG_SIGN[j] * design.b / 2.0) * t
                v = P + u[i, j] - D
                L = np.linalg.norm(v, axis=1)
                if half_l > 0:
                    leg_use[s:s + chunk] = np.maximum(leg_use[s:s + chunk], np.abs(L - l_mid) / half_l)
                au = jc[i, j, 0] * e + jc[i, j, 1] * t + jc[i, j, 2] * zaxis
                for axis in (au, np.broadcast_to(jc[i, j, 3:6], v.shape)):
                    cosang = np.clip(np.einsum("nk,nk->n", axis, v) / L, -1.0, 1.0)
                    angle[s:s + chunk] = np.maximum(angle[s:s + chunk], np.degrees(np.arccos(cosang)))

    def grid(values: np.ndarray) -> np.ndarray:
        out = np.full(occ.shape, np.nan)
        out[occ] = values
        return out

    return UsageMaps(stroke_use=grid(stroke_use), leg_use=grid(leg_use), joint_angle=grid(angle),
                     d=np.stack([grid(d_out[i]) for i in range(3)]), eta=np.stack([grid(e_out[i]) for i in range(3)]))


def usage_summary(maps: UsageMaps, bins: int = 20) -> dict[str, Any]:
    """Histograms (``bins`` equal bins) and extremes of the three maps over the reachable voxels."""
    out: dict[str, Any] = {}
    for name in ("stroke_use", "leg_use", "joint_angle"):
        v = getattr(maps, name)
        v = v[np.isfinite(v)]
        hi = 1.0 if name != "joint_angle" else max(90.0, float(v.max()) if v.size else 90.0)
        counts, edges = np.histogram(v, bins=bins, range=(0.0, hi))
        out[name] = {"min": float(v.min()) if v.size else None, "max": float(v.max()) if v.size else None,
                     "mean": float(v.mean()) if v.size else None, "counts": counts.tolist(),
                     "edges": [float(x) for x in edges]}
    return out

