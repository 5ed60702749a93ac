"""The constants of the compiled per-voxel reachability test, shared by the workspace engines and the
volume bracket.

Definition: at a fixed platform rotation ``R`` (eq. (2)) and ``n_eta`` arc samples, the kernels read
the tuple ``(u, cos_t, sin_t, arc, hb, rho_lo, rho_hi, lmin2, lmax2, jc)`` where ``u = p_local R^T``
are the platform's attachment points in the base frame (relative to the platform centre), the next
eight fields are :class:`kinematics.feasibility.ChainTables` (arc-sample directions, the stroke's end
and bisector directions, half the carriage's leg spacing, the radial stroke and the squared leg-length
limits), and ``jc`` is the joint-cone table of :func:`kinematics.joints.cone_table`.
"""

from __future__ import annotations

import numpy as np

from .design import Design
from .feasibility import ChainTables
from .geometry import platform_points_local
from .joints import Joints, cone_table
from .rotation import euler_zyx_deg

#: ``(u, cos_t, sin_t, arc, hb, rho_lo, rho_hi, lmin2, lmax2, jc)``
KernelArgs = tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, float, float, float, float, float, np.ndarray]


def kernel_args(design: Design, orientation_deg: object, n_eta: int, joints: Joints | None = None) -> KernelArgs:
    """Kernel constants; ``orientation_deg`` is ``(psi, theta, phi)`` or a 3x3 rotation matrix."""
    tab = ChainTables(design, n_eta)
    o = np.asarray(orientation_deg, dtype=float)
    rot = o if o.shape == (3, 3) else euler_zyx_deg(*o)
    u = np.ascontiguousarray(platform_points_local(design) @ rot.T)
    jc = cone_table(design, joints or Joints(), rot)
    return (u, tab.cos_t, tab.sin_t, tab.arc, tab.hb, tab.rho_lo, tab.rho_hi, tab.lmin2, tab.lmax2, jc)
