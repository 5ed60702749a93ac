"""Suite-wide set-up: compile every kernel a request can reach once, before any test runs
(kinematics/warmup.py), so that no request in a test waits on a numba compile however busy the
machine is (the kernels' on-disk cache then serves the CLI subprocesses too).

On a cold cache (a fresh clone, as CI runs it) that compile is a minute or more of one core: numba
compiles one kernel at a time. A helper process compiles, meanwhile, the kernels that warm_up()
reaches last (the general mechanism engine, the measures, the shell, the dexterity field, the task
answers and the orientation scan: about half of the compile, so that both cores finish together), into
the same on-disk cache, so that this process loads them instead of compiling them: the two cores
share the compile. The kernels and the results are the same either way (the helper only fills the
cache; warm_up() below still calls every kernel). With a warm cache no helper is started."""

from __future__ import annotations

import pathlib
import subprocess
import sys

import pytest

# The helper warms, in this order, what kinematics/warmup.warm_up() reaches last, in reverse.
_HELPER = r"""
import numpy as np
from paraspace.kinematics.mechanism_workspace import warm_up_general
warm_up_general()
from paraspace.kinematics.design import Design
from paraspace.kinematics.grid import GridSpec
from paraspace.kinematics.workspace import WorkspaceResult, WorkspaceSettings
h, lo, shape = 40.0, (-100.0, -100.0, 0.0), (5, 5, 4)
grid = GridSpec(origin=tuple(a + 0.5 * h for a in lo), h=h, shape=shape)
occ = np.zeros(shape, bool)
occ[1:4, 1:4, 2:4] = True
res = WorkspaceResult(design=Design(), settings=WorkspaceSettings(voxel=h, bounds=(lo, grid.hi)), grid=grid,
                      occupancy=occ, chain_mask=None, compute_seconds=0.0, n_eta=0)
from paraspace.kinematics.measures import measure_workspace
measure_workspace(res)
from paraspace.kinematics.shell import workspace_shell
workspace_shell(res)
from paraspace.kinematics.dexterity import dexterity_field
dexterity_field(res)
from paraspace.kinematics.task import OrientationSet, PoseList, Region, TaskSettings, pose_list_task, region_task
coarse = TaskSettings(voxel=8.0, margin_range=8.0)
region_task(Design(), Region("sphere", (0.0, 0.0, 130.0), (4.0,)), OrientationSet(tilt=5.0), coarse)
region_task(Design(), Region("box", (0.0, 0.0, 165.0), (10.0, 10.0, 10.0)), OrientationSet(), coarse)
pose_list_task(Design(), PoseList(np.array([[0.0, 0.0, 130.0, 0.0, 0.0, 0.0], [0.0, 0.0, 400.0, 0.0, 0.0, 0.0]])),
               coarse)
from paraspace.kinematics.orientation import OrientationSettings, orientation_workspace
orientation_workspace(Design(), OrientationSettings(angle_step=30.0, position_step=40.0))
"""


def _cache_is_cold() -> bool:
    """Whether numba's cache next to the core holds nothing of the general engine yet (its kernels
    are warmed last, so a cache that has them is warm)."""
    import os

    if os.environ.get("NUMBA_CACHE_DIR"):
        where = pathlib.Path(os.environ["NUMBA_CACHE_DIR"])
        return not any(where.rglob("mechanism_workspace.*.nbi"))
    from paraspace.kinematics import mechanism_workspace

    pycache = pathlib.Path(mechanism_workspace.__file__).parent / "__pycache__"
    return not any(pycache.glob("mechanism_workspace.*.nbi"))


@pytest.fixture(scope="session", autouse=True)
def warm_kernels() -> None:
    from paraspace.kinematics.warmup import warm_up

    helper = None
    if _cache_is_cold():
        helper = subprocess.Popen([sys.executable, "-c", _HELPER], stdout=subprocess.DEVNULL,
                                  stderr=subprocess.DEVNULL)
    try:
        warm_up()
    finally:
        if helper is not None and helper.poll() is None:  # nothing left for it to do: this process has it all
            helper.terminate()
            helper.wait(30)
