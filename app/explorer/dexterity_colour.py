"""Colour the displayed shell by the local dexterity ``1/kappa`` (issue 9) instead of the height.

:func:`field_colours` samples a :class:`~kinematics.dexterity.DexterityField` (computed on its own
coarser grid, h = :data:`DEXTERITY_VOXEL`) at the shell's vertices: every grid cell outside the
workspace takes the value of its nearest reachable cell (a Euclidean distance transform), and a
vertex takes the value of the cell it lies in. Colours: viridis over the field's range on the
workspace. :func:`binding_labels` names the limit that bounds the workspace at each surface point.
The explorer's View tab switches between "height z", "dexterity 1/kappa", "binding limit" and the
actuator-usage maps of :mod:`kinematics.usage` ("leg stroke use", "tightest joint angle";
:func:`values_colours`, on the dexterity field's grid).
"""

from __future__ import annotations

from typing import Any

import numpy as np
from scipy import ndimage as ndi

from paraspace.kinematics.shell import viridis

#: Voxel edge of the dexterity field shown on the shell (about 1 s on two cores for the default design).
DEXTERITY_VOXEL = 6.0
COLOUR_MODES: tuple[str, ...] = ("height z", "dexterity 1/kappa", "binding limit", "leg stroke use",
                                  "tightest joint angle")
#: The usage-map colour modes (:mod:`kinematics.usage`): mode -> (field of ``UsageMaps``, colour-bar
#: label, what the caption says).
USAGE_MODES: dict[str, tuple[str, str, str]] = {
    "leg stroke use": ("leg_use", "leg stroke use (0 mid-stroke, 1 at a limit)",
                       "the largest |l - l_mid| / (l_s/2) over the six legs at the resolved carriages"),
    "tightest joint angle": ("joint_angle", "largest joint angle (deg)",
                             "the largest angle between a leg and its U or S mount axis at the resolved carriages"),
}


def values_colours(mesh: Any, values: np.ndarray, origin: Any, h: float) -> tuple[Any, float, float]:
    """A copy of ``mesh`` coloured (viridis) by a grid field ``values`` (NaN outside the workspace)
    sampled at its vertices, and the field's range over the workspace."""
    vals = field_values_at(values, origin, h, mesh.vertices)
    finite = values[np.isfinite(values)]
    lo, hi = (float(finite.min()), float(finite.max())) if finite.size else (0.0, 1.0)
    u = (vals - lo) / (hi - lo) if hi > lo else np.zeros_like(vals)
    out = mesh.copy()
    out.visual.vertex_colors = viridis(np.nan_to_num(u))
    return out, lo, hi


def field_values_at(field: np.ndarray, origin: Any, h: float, points: np.ndarray) -> np.ndarray:
    """Values of a grid ``field`` (NaN outside the workspace) at ``points`` (N, 3): the value of the
    containing cell, NaN cells replaced by their nearest finite cell."""
    bad = ~np.isfinite(field)
    if bad.all():
        return np.full(len(points), np.nan)
    idx = ndi.distance_transform_edt(bad, return_distances=False, return_indices=True)
    filled = field[tuple(idx)]
    ijk = np.rint((np.asarray(points, float) - np.asarray(origin, float)) / h).astype(int)
    for a in range(3):
        ijk[:, a] = np.clip(ijk[:, a], 0, field.shape[a] - 1)
    return filled[ijk[:, 0], ijk[:, 1], ijk[:, 2]]


def field_colours(mesh: Any, dex: Any, result: Any) -> tuple[Any, float, float]:
    """A copy of ``mesh`` coloured by ``dex.inverse_condition`` (on ``result``'s grid), and the range."""
    vals = field_values_at(dex.inverse_condition, result.grid.origin, result.grid.h, mesh.vertices)
    lo, hi = float(dex.minimum), float(dex.maximum)
    u = (vals - lo) / (hi - lo) if hi > lo else np.zeros_like(vals)
    out = mesh.copy()
    out.visual.vertex_colors = viridis(np.nan_to_num(u))
    return out, lo, hi


#: Colours of the binding limits (:func:`binding_labels`): categorical and away from every
#: colour the mechanism uses for a state (legs blue / orange / red, platform green / red, the pinned
#: design magenta), so a leg seen through the shell never reads as a limit or the reverse.
LIMIT_COLOURS: dict[str, tuple[int, int, int]] = {
    "l_max": (235, 215, 0), "l_min": (0, 165, 165), "carriage strokes": (140, 90, 50),
    "joint cones": (125, 75, 195), "interference": (55, 55, 55), "other": (205, 205, 205),
}
#: Their names, as the Legend says them.
LIMIT_COLOUR_NAMES: dict[str, str] = {
    "l_max": "yellow", "l_min": "teal", "carriage strokes": "brown", "joint cones": "purple",
    "interference": "dark grey", "other": "light grey",
}


def binding_labels(design: Any, settings: Any, points: np.ndarray, normals: np.ndarray, step: float) -> list[str]:
    """Which limit bounds the workspace at each surface point (our definition, for the colours):
    at ``p + step n`` (just outside, ``n`` the outward normal) a chain fails; the first of these
    relaxations that makes every failing chain feasible names the limit: ``l_max`` (legs longer by
    ``2 step``), ``l_min`` (shorter by ``2 step``), ``carriage strokes`` (``d_s`` and ``eta_s`` larger
    by 20 %), ``joint cones`` (no cones); ``interference`` when the chains pass alone but the legs
    collide; ``other`` when none does."""
    import dataclasses

    from paraspace.kinematics.joints import Joints
    from paraspace.kinematics.workspace import ALL_CHAINS, chain_masks_at, reachable

    out_pts = np.asarray(points, float) + step * np.asarray(normals, float)
    o, eta_step, j = settings.orientation, settings.eta_step, settings.joints
    base = chain_masks_at(design, out_pts, o, eta_step, j)
    labels = np.full(len(out_pts), "other", dtype=object)
    todo = base != ALL_CHAINS
    if j.min_distance > 0:
        inter = (~todo) & ~reachable(design, out_pts, o, eta_step, j)
        labels[inter] = "interference"
    relaxations = (
        ("l_max", design.replace(l_s=design.l_s + 2 * step), j),
        ("l_min", design.replace(l_min=max(design.l_min - 2 * step, 1e-6), l_s=design.l_s + 2 * step), j),
        ("carriage strokes", design.replace(d_s=min(design.r, 1.2 * design.d_s + 1.0),
                                            eta_s=min(180.0, 1.2 * design.eta_s + 1.0)), j),
        ("joint cones", design, dataclasses.replace(j, theta_u=None, theta_s=None) if j.has_cones else Joints()),
    )
    for name, d2, j2 in relaxations:
        idx = np.flatnonzero(todo & (labels == "other"))
        if not idx.size:
            break
        m = chain_masks_at(d2, out_pts[idx], o, eta_step, j2)
        fixed = (m & ~base[idx] & ALL_CHAINS) == (~base[idx] & ALL_CHAINS)
        labels[idx[fixed]] = name
    return list(labels)
