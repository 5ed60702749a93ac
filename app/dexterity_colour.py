"""Colour the displayed shell by the local dexterity ``1/kappa`` (issue 9) instead of the height.

:func:`field_colours` samples a :class:`~kinematics.dexterity.DexterityField` (computed on its own
coarser grid, h = :data:`DEXTERITY_VOXEL`) at the shell's vertices: every grid cell outside the
workspace takes the value of its nearest reachable cell (a Euclidean distance transform), and a
vertex takes the value of the cell it lies in. Colours: viridis over the field's range on the
workspace. The explorer's View tab switches between "height z" and "dexterity 1/kappa".
"""

from __future__ import annotations

from typing import Any

import numpy as np
from scipy import ndimage as ndi

from paraspace.kinematics.shell import viridis

#: Voxel edge of the dexterity field shown on the shell (about 1 s on two cores for the default design).
DEXTERITY_VOXEL = 6.0
COLOUR_MODES: tuple[str, ...] = ("height z", "dexterity 1/kappa")


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
