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


def test_parallel_advance_equals_the_serial_one():
    """Issue 24 target 7: the parallel ``_advance`` (counts, prefix sum, children at their offsets)
    returns exactly the arrays of the former serial loop (``_advance_serial``) and writes the same
    voxels, level after level on random chain states and windows (so later levels see mixed block
    sizes), both modes, with 1 and 2 threads and the chunked launches of the engine."""
    import numba

    from paraspace.kinematics import blocks
    from paraspace.kinematics.parallel import kernel_launch

    rng = np.random.default_rng(24)
    threads = numba.get_num_threads()
    try:
        for n_threads in sorted({1, min(2, numba.config.NUMBA_NUM_THREADS)}):
            numba.set_num_threads(n_threads)
            for shape, all_chains in (((37, 29, 21), False), ((33, 18, 40), True), ((16, 16, 16), False)):
                b0, bn = blocks._top_blocks(shape, 8)
                out_ref = np.full(shape, 255, np.uint8)
                out_new = out_ref.copy()
                levels = 0
                while b0.shape[0]:
                    state = rng.choice(np.array([0, 1, 2], np.int8), size=(b0.shape[0], 3), p=[0.5, 0.3, 0.2])
                    win = rng.integers(-5, 1000, size=(b0.shape[0], 3, 3), dtype=np.int64)
                    ref = blocks._advance_serial(b0, bn, state, win, all_chains, out_ref)
                    with kernel_launch(b0.shape[0]):
                        new = blocks._advance(b0, bn, state.copy(), win.copy(), all_chains, out_new)
                    for r, n in zip(ref, new):
                        assert r.dtype == n.dtype and np.array_equal(r, n), (n_threads, shape, levels)
                    assert np.array_equal(out_ref, out_new), (n_threads, shape, levels)
                    b0, bn = ref[0], ref[1]
                    levels += 1
                assert levels >= 4 and not (out_new == 255).any()  # every voxel decided, each once
    finally:
        numba.set_num_threads(threads)
