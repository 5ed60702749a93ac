"""The coarse-to-fine engine (kinematics.blocks) is voxel-identical to the dense engine (the oracle)
for every orientation, both arc ranges, mirror on and off, and in diagnostics mode per chain."""

from __future__ import annotations

import dataclasses
import random

import numpy as np
import pytest

from paraspace.kinematics.design import PARAMS, Design, ParameterError
from paraspace.kinematics.workspace import WorkspaceSettings, compute_workspace

CASES = [
    (Design(), dict(voxel=4.0)),
    (Design(a=10), dict(voxel=4.0)),  # incomplete workspace, thin caps
    (Design(a=80, d_s=80), dict(voxel=5.0)),
    (Design(eta_range="from-zero"), dict(voxel=4.0)),
    (Design(), dict(voxel=4.0, orientation=(10.0, 5.0, -8.0))),
    (Design(), dict(voxel=3.0, orientation=(0.0, 25.0, 0.0))),
    (Design(), dict(voxel=4.0, symmetry=False)),
    (Design(), dict(voxel=6.0, diagnostics=True)),
    (Design(a=10, eta_range="from-zero"), dict(voxel=5.0, diagnostics=True, orientation=(30.0, 0.0, 10.0))),
    (Design(eta_s=0, d_s=0), dict(voxel=5.0)),  # a plain 6-UPS
    (Design(), dict(voxel=2.5, bounds=((-60.0, -40.0, 90.0), (70.0, 55.0, 170.0)))),  # odd explicit box
]


def _both(design: Design, **kw):
    dense = compute_workspace(design, WorkspaceSettings(method="dense", **kw))
    blocks = compute_workspace(design, WorkspaceSettings(method="blocks", **kw))
    return dense, blocks


@pytest.mark.parametrize("design,kw", CASES)
def test_blocks_equal_dense(design, kw):
    dense, blocks = _both(design, **kw)
    assert dense.grid == blocks.grid
    assert np.array_equal(dense.occupancy, blocks.occupancy), (dense.voxels, blocks.voxels)
    if kw.get("diagnostics"):
        assert np.array_equal(dense.chain_mask, blocks.chain_mask)
    assert dense.voxels > 0 or design.eta_s == 0


def test_blocks_equal_dense_on_random_designs():
    rng = random.Random(7)
    for _ in range(6):
        fields = {n: rng.uniform(s.slider_min, s.slider_max) for n, s in PARAMS.items() if n not in ("b", "r", "l_min")}
        fields["d_s"] = min(fields["d_s"], 100.0)
        design = Design(**fields, eta_range=rng.choice(["centered", "from-zero"]))
        o = (rng.uniform(-30, 30), rng.uniform(-20, 20), rng.uniform(-20, 20)) if rng.random() < 0.5 else (0.0, 0.0, 0.0)
        dense, blocks = _both(design, voxel=6.0, orientation=o)
        assert np.array_equal(dense.occupancy, blocks.occupancy), (design, o)


def test_method_is_validated():
    with pytest.raises(ParameterError) as e:
        WorkspaceSettings(method="fast")
    assert e.value.field == "method"
    assert dataclasses.replace(WorkspaceSettings(), method="dense").method == "dense"


def test_fused_finish_equals_the_numpy_mirror_fill_and_completion_test():
    """Issue 24 target 7: the fused last pass of ``_run_grid`` (mirror rows and ``== 7`` in one
    parallel kernel) equals the numpy steps it replaced, on several designs with and without the
    mirror."""
    import numpy as np

    from paraspace.kinematics import workspace
    from paraspace.kinematics.design import Design
    from paraspace.kinematics.workspace import WorkspaceSettings, compute_workspace

    for design, orientation in ((Design(), (0.0, 0.0, 0.0)), (Design(a=10), (0.0, 0.0, 0.0)),
                                (Design(l_s=20), (10.0, 5.0, 0.0))):
        res = compute_workspace(design, WorkspaceSettings(voxel=6.0, orientation=orientation, diagnostics=True))
        half = res.chain_mask.copy()
        ny = half.shape[1]
        mirror = workspace._use_mirror(design, res.settings, res.grid)
        ny_eval = (ny + 1) // 2 if mirror else ny
        half[:, ny_eval:] = 0
        ref = half.copy()
        if mirror:
            ref[:, ny_eval:] = workspace._MIRROR_BITS[ref[:, : ny - ny_eval]][:, ::-1]
        occ = np.empty(half.shape, bool)
        workspace._finish_kernel(half, ny_eval, mirror, workspace._MIRROR_BITS, occ)
        assert np.array_equal(half, ref) and np.array_equal(occ, ref == 7) and np.array_equal(occ, res.occupancy)
