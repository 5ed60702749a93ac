"""paraspace.kinematics: the pure numerical core (no web imports).

Model, inverse/forward kinematics, redundancy resolution, Jacobians and mobility of the
3-(arc-P, P, 2-(UPS)) redundant parallel mechanism; its position and orientation workspaces,
their measures, shells and parameter studies.
"""

from .design import PARAMS, Design, ParameterError
from .grid import GridSpec
from .pose import Pose
from .progress import Cancelled
from .workspace import WorkspaceResult, WorkspaceSettings, compute_workspace, reachable

__all__ = [
    "PARAMS", "Design", "ParameterError", "GridSpec", "Pose", "Cancelled",
    "WorkspaceResult", "WorkspaceSettings", "compute_workspace", "reachable",
]
