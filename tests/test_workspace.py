"""The position-workspace engine against independent computations."""

from __future__ import annotations

import threading

import numpy as np
import pytest

from paraspace.kinematics.design import Design, ParameterError
from paraspace.kinematics.grid import GridSpec
from paraspace.kinematics.progress import Cancelled
from paraspace.kinematics.reference import gough_stewart_reachable, reference_reachable
from paraspace.kinematics.rotation import rot_z
from paraspace.kinematics.workspace import WorkspaceSettings, compute_workspace, reachable

DESIGN = Design()
BOX = ((-180.0, -180.0, 0.0), (180.0, 180.0, 165.0))


@pytest.mark.parametrize("design,orientation", [
    (DESIGN, (0.0, 0.0, 0.0)),
    (Design(eta_range="from-zero", a=70, d_s=30), (0.0, 0.0, 0.0)),
    (DESIGN, (10.0, -6.0, 4.0)),
])
def test_engine_agrees_voxel_by_voxel_with_brute_force(design, orientation):
    res = compute_workspace(design, WorkspaceSettings(voxel=9.0, bounds=BOX, orientation=orientation))
    ref = reference_reachable(design, res.grid.points().reshape(-1, 3), orientation).reshape(res.grid.shape)
    assert ref.sum() > 1000
    assert np.array_equal(res.occupancy, ref), f"{(res.occupancy != ref).sum()} voxels differ"


def test_gough_stewart_special_case():
    """d_s = eta_s = 0 is a plain 6-UPS platform: compare with the direct leg-length check."""
    gs = Design(d_s=0, eta_s=0)
    for orientation in [(0.0, 0.0, 0.0), (5.0, 3.0, -2.0)]:
        res = compute_workspace(gs, WorkspaceSettings(voxel=3.0, bounds=BOX, orientation=orientation))
        ref = gough_stewart_reachable(gs, res.grid.points().reshape(-1, 3), orientation).reshape(res.grid.shape)
        assert ref.sum() > 100
        assert np.array_equal(res.occupancy, ref)


def test_threefold_symmetry_at_zero_rotation():
    rng = np.random.default_rng(0)
    pts = np.column_stack([rng.uniform(-170, 170, 20000), rng.uniform(-170, 170, 20000), rng.uniform(0, 165, 20000)])
    for design in [DESIGN, Design(eta_range="from-zero", b=20, a=35)]:
        base = reachable(design, pts)
        assert 1000 < base.sum() < 19000
        for k in (1, 2):
            rotated = reachable(design, pts @ rot_z(2 * np.pi * k / 3).T)
            assert (rotated != base).sum() <= 2  # float ties only


def test_mirror_shortcut_equals_full_computation():
    a = compute_workspace(DESIGN, WorkspaceSettings(voxel=5.0, bounds=BOX, symmetry=True))
    b = compute_workspace(DESIGN, WorkspaceSettings(voxel=5.0, bounds=BOX, symmetry=False))
    assert np.array_equal(a.occupancy, b.occupancy)
    c = compute_workspace(DESIGN, WorkspaceSettings(voxel=5.0, bounds=BOX, diagnostics=True))
    d = compute_workspace(DESIGN, WorkspaceSettings(voxel=5.0, bounds=BOX, diagnostics=True, symmetry=False))
    assert np.array_equal(c.chain_mask, d.chain_mask)
    assert np.array_equal(c.occupancy, a.occupancy)


@pytest.mark.parametrize("param,values", [("l_s", [20, 40, 60, 80]), ("eta_s", [10, 30, 60, 90]), ("d_s", [10, 30, 60])])
def test_volume_grows_with_strokes(param, values):
    """A longer stroke only adds carriage/leg poses, so the reachable set can only grow (same samples
    when the arc samples nest: eta_step divides the stroke)."""
    vols = []
    prev = None
    for v in values:
        r = compute_workspace(DESIGN.replace(**{param: v}), WorkspaceSettings(voxel=6.0, bounds=BOX, eta_step=0.5))
        if prev is not None and param != "eta_s":
            assert np.all(r.occupancy >= prev)  # pointwise inclusion
        prev = r.occupancy
        vols.append(r.volume)
    assert all(b >= a for a, b in zip(vols, vols[1:])) and vols[-1] > vols[0]


def test_default_bounds_contain_the_workspace():
    for design in [DESIGN, Design(a=10), Design(l_s=100, eta_s=100), Design(d_s=100)]:
        res = compute_workspace(design, WorkspaceSettings(voxel=6.0))
        occ = res.occupancy
        assert occ.any()
        for axis in range(3):
            assert not np.take(occ, -1, axis=axis).any()
            if axis < 2:
                assert not np.take(occ, 0, axis=axis).any()
        wide = compute_workspace(design, WorkspaceSettings(voxel=6.0, bounds=((-420, -420, 0), (420, 420, 270))))
        assert wide.volume == pytest.approx(res.volume, rel=0.01)


def test_volume_converges_in_voxel_size_and_eta_step():
    fine = compute_workspace(DESIGN, WorkspaceSettings(voxel=2.0, eta_step=0.25)).volume
    coarse = compute_workspace(DESIGN, WorkspaceSettings(voxel=2.0, eta_step=0.5)).volume
    assert abs(coarse - fine) / fine < 0.003
    assert 5.0e6 < fine < 5.25e6  # the converged value 5.12e6 (centered eta range)


def test_progress_and_cancellation():
    seen = []
    compute_workspace(DESIGN, WorkspaceSettings(voxel=4.0, bounds=BOX), progress=lambda f, m: seen.append(f))
    assert seen and seen[-1] == 1.0 and all(b >= a for a, b in zip(seen, seen[1:]))
    ev = threading.Event()
    calls = []

    def cancel_soon(f, m):
        calls.append(f)
        if len(calls) == 2:
            ev.set()
    with pytest.raises(Cancelled):
        compute_workspace(DESIGN, WorkspaceSettings(voxel=2.0, bounds=BOX), progress=cancel_soon, cancel=ev)


def test_the_engine_progress_counts_its_levels_and_blocks():
    """The blocks engine's progress names its level out of all of them and, of the blocks it tested,
    how many smaller ones come next: at most 8 per block tested, none after the last level (it read
    "refining 1,648 boundary blocks of 432" before: the children counted against their parents)."""
    import re

    msgs = []
    compute_workspace(DESIGN, WorkspaceSettings(voxel=4.0, bounds=BOX), progress=lambda f, m: msgs.append(m))
    rows = [tuple(int(g.replace(",", "")) if g else 0 for g in m.groups())
            for m in (re.search(r"level (\d+) of (\d+): ([\d,]+) blocks tested(?:, ([\d,]+) smaller ones)?", t)
                      for t in msgs) if m]
    assert len(rows) >= 3
    assert [r[0] for r in rows] == list(range(1, len(rows) + 1)) and {r[1] for r in rows} == {len(rows)}
    assert all(0 < nxt <= 8 * tested for _, _, tested, nxt in rows[:-1])
    assert all(rows[k + 1][2] == rows[k][3] for k in range(len(rows) - 1))
    last = [t for t in msgs if "blocks tested" in t][-1]
    assert "next" not in last and last.endswith(f"level {len(rows)} of {len(rows)}: {rows[-1][2]:,} blocks tested)")


def test_bad_settings_name_the_field():
    with pytest.raises(ParameterError, match="voxel"):
        WorkspaceSettings(voxel=0)
    with pytest.raises(ParameterError, match="theta"):
        WorkspaceSettings(orientation=(0, 120, 0))
    with pytest.raises(ParameterError, match="bounds"):
        WorkspaceSettings(bounds=((0, 0, 0), (-1, 1, 1)))


def test_grid_spec_covers_box():
    g = GridSpec.from_bounds((-180, -180, 0), (180, 180, 165), 2.0)
    assert g.shape == (180, 180, 83) and g.is_mirror_symmetric_y()
    assert g.lo == (-180, -180, 0) and g.hi[2] >= 165


def test_reachable_pairs_equals_one_call_per_orientation():
    """The orientation scan's single launch over (position, angle) pairs gives exactly the
    per-orientation reachable() calls it replaced."""
    from paraspace.kinematics.orientation import rotation_matrix
    from paraspace.kinematics.workspace import reachable_pairs

    rng = np.random.default_rng(5)
    for design in (Design(), Design(a=30, eta_range="from-zero")):
        pts = np.column_stack([rng.uniform(-120, 120, 300), rng.uniform(-120, 120, 300), rng.uniform(60, 220, 300)])
        rots = [rotation_matrix(rt, a) for rt in ("phi_z", "tau_yprime", "psi_x") for a in (-60.0, -12.5, 0.0, 33.0, 80.0)]
        pairs = reachable_pairs(design, pts, np.stack(rots))
        loop = np.stack([reachable(design, pts, R) for R in rots], axis=1)
        assert np.array_equal(pairs, loop)
        assert 0 < pairs.sum() < pairs.size


@pytest.mark.parametrize("z_floor,h", [(20.0, 3.0), (21.0, 4.0), (7.5, 2.0)])
def test_a_floor_off_the_grid_starts_the_grid_at_the_floor(z_floor, h):
    """A z_floor that is not a multiple of the voxel edge used to start the grid a layer below the
    floor, so every design touched the box's bottom off the floor and was reported incomplete."""
    from paraspace.kinematics.measures import measure_workspace

    r = compute_workspace(Design(), WorkspaceSettings(voxel=h, z_floor=z_floor))
    assert r.grid.lo[2] == pytest.approx(z_floor)
    assert r.grid.axes()[2].min() >= z_floor
    m = measure_workspace(r)
    assert m.boundary_complete, m.completeness_reason
    fine = compute_workspace(Design(), WorkspaceSettings(voxel=2.0, z_floor=z_floor,
                                                         bounds=((-200.0, -200.0, z_floor), (200.0, 200.0, 260.0))))
    assert r.volume == pytest.approx(fine.volume, rel=0.03)
