"""Compile every numba kernel a request can reach, once, before the first request.

numba compiles a kernel on its first call (tens of seconds on a busy machine) and keeps the
machine code in its on-disk cache (``cache=True`` on every kernel): a later process loads it in
about a second. A server therefore calls :func:`warm_up` at start-up (in a background thread, with
a line on the console when it is done), so that no request waits on a compile; the test suite's
fixtures call it before they send a request.

"Every kernel a request can reach" is every entry point of the core on a tiny problem: the
workspace engines (blocks and dense, with diagnostics, the certified bracket and the mirror), the
per-point test with and without joint cones about both axes and with leg interference, the
redundancy resolution with joints (the explorer's pose panel and ``/ik``), the orientation line
scan, the task answers (region and pose list: the certification and pose kernels), the dexterity
field, the measures and shell of a result, and the general engine of a mechanism description
(:mod:`kinematics.mechanism_workspace`).
"""

from __future__ import annotations

import threading
import time

import numpy as np

from .design import Design
from .joints import Joints
from .pose import Pose

__all__ = ["warm_up", "is_warm"]

_lock = threading.Lock()
_warm = False


def is_warm() -> bool:
    """Whether :func:`warm_up` has run to its end in this process."""
    return _warm


def warm_up() -> float:
    """Compile (or load from numba's cache) every kernel requests reach; returns the seconds it
    took (0 when already done in this process). Thread-safe: concurrent callers wait for one run."""
    global _warm
    t0 = time.perf_counter()
    with _lock:
        if _warm:
            return 0.0
        from .dexterity import dexterity_field
        from .measures import measure_workspace
        from .orientation import OrientationSettings, orientation_workspace
        from .redundancy import resolve_redundancy
        from .shell import workspace_shell
        from .workspace import WorkspaceSettings, compute_workspace, reachable

        d = Design()
        box = ((-100.0, -100.0, 0.0), (100.0, 100.0, 160.0))
        res = compute_workspace(d, WorkspaceSettings(voxel=40.0, bounds=box))
        compute_workspace(d, WorkspaceSettings(voxel=40.0, bounds=box, diagnostics=True, bracket=True))
        compute_workspace(d, WorkspaceSettings(voxel=40.0, bounds=box, method="dense"))
        pts = np.array([[0.0, 0.0, 130.0], [10.0, 5.0, 120.0]])
        for joints in (Joints(), Joints(theta_u=45.0, theta_s=45.0), Joints(theta_u=30.0, cone_axis="home"),
                       Joints(leg_diameter=10.0, clearance=1.0)):
            reachable(d, pts, (0.0, 0.0, 0.0), joints=joints)
            reachable(d, pts, (5.0, 3.0, 2.0), joints=joints)
            resolve_redundancy(d, Pose(z=130.0), joints)
            compute_workspace(d, WorkspaceSettings(voxel=40.0, bounds=box, joints=joints))
        orientation_workspace(d, OrientationSettings(angle_step=30.0, position_step=40.0))
        from .task import OrientationSet, PoseList, Region, TaskSettings, pose_list_task, region_task

        coarse = TaskSettings(voxel=8.0, margin_range=8.0)
        region_task(d, Region("sphere", (0.0, 0.0, 130.0), (4.0,)), OrientationSet(tilt=5.0), coarse)
        region_task(d, Region("box", (0.0, 0.0, 165.0), (10.0, 10.0, 10.0)), OrientationSet(), coarse)
        pose_list_task(d, PoseList(np.array([[0.0, 0.0, 130.0, 0.0, 0.0, 0.0], [0.0, 0.0, 400.0, 0.0, 0.0, 0.0]])),
                       coarse)
        for search in ("neighbour", "sweep"):  # the full search's kernels: the neighbour's run-time check
            dexterity_field(res, search=search)
        measure_workspace(res)
        from .run_components import RunComponents

        RunComponents(np.ones((2, 2, 2), bool)).mask(np.ones(1, bool))  # the pieces' mask: only with fragments
        workspace_shell(res)
        from .mechanism_workspace import warm_up_general

        warm_up_general()
        _warm = True
    return time.perf_counter() - t0
