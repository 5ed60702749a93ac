"""paraspace: workspace of the 3-(arc-P, P, 2-(UPS)) kinematically redundant parallel mechanism.

The installed distribution is one namespace:

- ``paraspace.kinematics``: the pure numerical core (no web package), the repository's ``kinematics/``;
- ``paraspace.app``: the explorer, REST API and CLI, the repository's ``app/``;
- ``paraspace.static``: web assets, the repository's ``static/``.

The names below re-export the core for scripts and notebooks::

    import paraspace as ps
    res = ps.compute_workspace(ps.Design(), ps.WorkspaceSettings(voxel=4.0))
    print(res.volume)
"""

from __future__ import annotations

import importlib
import importlib.metadata
import pathlib
from typing import Any

# In a source checkout the sub-packages sit beside this folder (kinematics/, app/, static/), while
# an installed copy holds them inside it (setuptools' package-dir in pyproject.toml). Let a
# checkout import itself the same way the installed package does.
_here = pathlib.Path(__file__).resolve().parent
if not (_here / "kinematics").is_dir() and (_here.parent / "kinematics" / "__init__.py").is_file():
    __path__.append(str(_here.parent))

try:
    __version__: str = importlib.metadata.version("paraspace")
except importlib.metadata.PackageNotFoundError:  # a checkout that was never installed
    __version__ = "0+unknown"

_CORE = (
    "PARAMS", "Design", "ParameterError", "GridSpec", "Pose", "Cancelled",
    "WorkspaceResult", "WorkspaceSettings", "compute_workspace", "reachable",
    "resolve_redundancy", "inverse_kinematics", "forward_kinematics", "jacobians", "mobility",
    "measure_workspace", "WorkspaceMeasures", "workspace_shell", "export_shell",
    "orientation_workspace", "OrientationSettings",
    "sweep_1d", "sweep_2d", "evaluate_design", "ResultCache",
)


def __getattr__(name: str) -> Any:
    if name in _CORE:
        return getattr(importlib.import_module(".kinematics", __name__), name)
    raise AttributeError(f"module 'paraspace' has no attribute {name!r}")


def __dir__() -> list[str]:
    return sorted([*globals(), *_CORE])


__all__ = ["__version__", *_CORE]
