"""The benchmarks' "before" paths are the real former paths: `benchmarks/bench_workspace.py`
prints each issue-24 step beside the path it replaced, and a ratio against a broken or different
"before" would mean nothing. (A lost decorator once made the leg-interference row raise before it
printed, which nothing caught.)"""

from __future__ import annotations

import importlib.util
import pathlib

import numpy as np

from paraspace.kinematics.design import Design
from paraspace.kinematics.joints import Joints
from paraspace.kinematics.workspace import WorkspaceSettings, compute_workspace

_BENCH = pathlib.Path(__file__).resolve().parents[1] / "benchmarks" / "bench_workspace.py"


def _bench():
    spec = importlib.util.spec_from_file_location("bench_workspace_under_test", _BENCH)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_the_per_voxel_interference_row_runs_the_witness_search_at_every_voxel_and_restores_the_engine():
    from paraspace.kinematics import workspace

    bench = _bench()
    settings = WorkspaceSettings(voxel=12.0, joints=Joints(leg_diameter=10.0))
    blocks = compute_workspace(Design(), settings)
    engine_path = workspace.interference_free_grid
    calls = []

    with bench._per_voxel_interference():
        patched = workspace.interference_free_grid
        assert patched is not engine_path

        def counted(*args, **kwargs):
            calls.append(int(np.count_nonzero(args[6])))
            return patched(*args, **kwargs)

        workspace.interference_free_grid = counted
        try:
            per_voxel = compute_workspace(Design(), settings)
        finally:
            workspace.interference_free_grid = patched
    assert workspace.interference_free_grid is engine_path
    # the former path was taken, on voxels the chains reach, and gives the blocks' voxels exactly
    assert calls and sum(calls) > 0
    assert np.array_equal(per_voxel.occupancy, blocks.occupancy)
    assert 0 < blocks.voxels < compute_workspace(Design(), WorkspaceSettings(voxel=12.0)).voxels
