"""paraspace.kinematics: the pure numerical core (no web imports).

Model, inverse/forward kinematics, redundancy resolution, Jacobians and mobility of the
3-(arc-P, P, 2-(UPS)) redundant parallel mechanism; its position and orientation workspaces,
their measures, shells and parameter studies; dexterity (1/kappa, GCI), the tilt-and-torsion
orientation report and the total-orientation workspace.

Heavier modules (measures, shell, orientation, sweep, distributed) import lazily, so
``import kinematics`` stays cheap.
"""

from __future__ import annotations

import importlib
from typing import Any

from . import numba_cache  # noqa: F401  first: installs the cache locators before any kernel is decorated
from .design import PARAMS, Design, ParameterError
from .forward import forward_kinematics
from .grid import GridSpec
from .jacobian import jacobians
from .mobility import mobility
from .pose import Pose
from .progress import Cancelled
from .redundancy import inverse_kinematics, resolve_redundancy
from .workspace import WorkspaceResult, WorkspaceSettings, compute_workspace, reachable

_LAZY = {
    "measure_workspace": "measures", "WorkspaceMeasures": "measures",
    "workspace_shell": "shell", "export_shell": "shell",
    "orientation_workspace": "orientation", "OrientationSettings": "orientation",
    "sweep_1d": "sweep", "sweep_2d": "sweep", "evaluate_design": "sweep", "ResultCache": "sweep",
    "dexterity_at": "dexterity", "dexterity_field": "dexterity",
    "tilt_torsion_at": "tilt_torsion", "TiltTorsionSettings": "tilt_torsion",
    "total_orientation_workspace": "dexterous",
    "compute_mechanism_workspace": "mechanism_workspace", "mechanism_ik": "mechanism_workspace",
    "sweep_preset": "sweep", "mechanism_jacobians": "mechanism_jacobian",
    "mechanism_orientation_workspace": "mechanism_orientation", "mechanism_total_orientation": "mechanism_orientation",
    "mechanism_dexterity_field": "mechanism_dexterity",
}


def __getattr__(name: str) -> Any:
    if name in _LAZY:
        return getattr(importlib.import_module(f".{_LAZY[name]}", __name__), name)
    raise AttributeError(name)


__all__ = [
    "PARAMS", "Design", "ParameterError", "GridSpec", "Pose", "Cancelled",
    "WorkspaceResult", "WorkspaceSettings", "compute_workspace", "reachable",
    "resolve_redundancy", "inverse_kinematics", "forward_kinematics", "jacobians", "mobility", *_LAZY,
]
