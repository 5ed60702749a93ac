"""Work limits shared by every entry point that starts a computation for someone else.

One rule for the size of a workspace grid, checked *before* any work is queued, with one message:
the REST API (``/workspace``, ``/sweep`` per point, ``/orientation``) and the browser explorer
(whatever a link or a slider asks for) all call :func:`check_workspace_grid`. The command line
runs on the user's own machine and is not capped.

Memory: a workspace job holds its occupancy grid (1 byte a voxel) plus the padded fields of the
marching-cubes shell and the label arrays of the measures, about 25 bytes a voxel at the peak
(measured in the README's "Security model and limits"); :data:`MAX_VOXELS` bounds one job.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from paraspace.kinematics.design import Design, ParameterError

__all__ = ["MAX_VOXELS", "grid_voxels", "workspace_voxels", "orientation_samples", "check_workspace_grid",
           "check_mechanism_grid"]

#: Largest workspace grid one request may ask for. The paper's default design at voxel 1 (the
#: finest explorer setting) needs 20.8 million voxels; a Table I design with every length at its
#: maximum needs 45.7 million at voxel 1 and 13.5 million at voxel 1.5.
MAX_VOXELS = 25_000_000


def grid_voxels(lo: tuple[float, ...], hi: tuple[float, ...], h: float) -> int:
    """Voxels of the grid of edge ``h`` covering the box ``[lo, hi]`` (as the engine lays it)."""
    return int(np.prod([max(1, math.ceil((b - a) / h - 1e-9)) for a, b in zip(lo, hi)], dtype=object))


def workspace_voxels(design: Design, settings: Any, *, analytic: bool = False) -> int:
    """Voxels of the grid a workspace request runs on, computed before running.

    Explicit bounds: exactly the grid of the box. Derived bounds: the box of
    ``kinematics.workspace.default_bounds`` (``analytic=False``; runs a coarse scout of about
    50^3 voxels) or the analytical reach box (``analytic=True``: no computation, an upper bound).
    """
    from paraspace.kinematics import workspace as ws

    h = settings.voxel
    if settings.bounds is not None:
        lo, hi = settings.bounds
    elif analytic:
        lo, hi = ws._symmetric_box(*ws.reach_box(design, settings.orientation, settings.z_floor), h, settings.z_floor)
    else:
        lo, hi = ws.default_bounds(design, settings)
    return grid_voxels(lo, hi, h)


def orientation_samples(design: Design, settings: Any) -> int:
    """Position x angle samples of an orientation workspace (3 lines x 3 rotations)."""
    from paraspace.kinematics import orientation as ori

    n_ang = int(ori.angle_samples(settings).size)
    n_pos = sum(int(ori.position_samples(design, ln, settings).size) for ln in ori.LINES)
    return n_pos * n_ang * len(ori.ROTATIONS)


def check_workspace_grid(design: Design, settings: Any, max_voxels: int = MAX_VOXELS, *,
                         analytic: bool = False) -> int:
    """The grid's voxel count, or :class:`ParameterError` on ``voxel`` when it exceeds ``max_voxels``.

    The message names the smallest voxel edge that fits (the count scales as ``h^-3``; rounded
    up to the next 0.1), the limit and the count.
    """
    n = workspace_voxels(design, settings, analytic=analytic)
    if n > max_voxels:
        h = float(settings.voxel)
        need = math.ceil(h * (n / max_voxels) ** (1.0 / 3.0) * 10.0 + 1e-9) / 10.0
        raise ParameterError("voxel", h, f"voxel >= {need:g} for this design (a grid of at most "
                                         f"{max_voxels:,} voxels; voxel {h:g} makes {n:,})")
    return n


def check_mechanism_grid(mech: Any, settings: Any, max_voxels: int = MAX_VOXELS, length_step: float = 1.0) -> int:
    """:func:`check_workspace_grid` for a mechanism description on the general engine (its grid is
    laid by ``kinematics.mechanism_workspace.general_plan``): the same rule and message."""
    from paraspace.kinematics.mechanism_workspace import general_plan

    grid, _samples = general_plan(mech, settings, length_step)
    n = int(grid.size)
    if n > max_voxels:
        h = float(settings.voxel)
        need = math.ceil(h * (n / max_voxels) ** (1.0 / 3.0) * 10.0 + 1e-9) / 10.0
        raise ParameterError("voxel", h, f"voxel >= {need:g} for this mechanism (a grid of at most "
                                         f"{max_voxels:,} voxels; voxel {h:g} makes {n:,})")
    return n
