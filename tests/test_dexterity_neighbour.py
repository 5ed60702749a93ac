"""Issue 24 target 3: the dexterity field's neighbour search (kinematics/dexterity_neighbour.py)
against the resolver's full search (resolved_carriages, the slow path) at every voxel of coarse
workspaces of several designs, the stated tolerance on the margin, and its run-time check."""

from __future__ import annotations

import json
import math
import subprocess
import sys

import numpy as np
import pytest

from paraspace.kinematics.design import Design, ParameterError
from paraspace.kinematics.dexterity import dexterity_field, inverse_condition_batch, resolved_carriages
from paraspace.kinematics.dexterity_neighbour import (
    MARGIN_TOLERANCE,
    SAMPLE_MAX,
    SAMPLE_MIN,
    _NEAR_START,
    chain_margins,
    compare,
    mirror_rows,
    neighbour_field,
    sample_indices,
)
from paraspace.kinematics.dexterity_sweep import TOL_ABS, TOL_REL
from paraspace.kinematics.inverse import leg_lengths, leg_margin
from paraspace.kinematics.pose import Pose
from paraspace.kinematics.workspace import WorkspaceSettings, compute_workspace

CASES = [(Design(), 10.0, (0.0, 0.0, 0.0)),
         (Design(a=30, b=20, eta_s=60), 10.0, (8.0, -5.0, 3.0)),
         (Design(d_s=80, eta_s=45), 12.0, (0.0, 0.0, 0.0))]


def _margins_from_ik(design: Design, point, orientation, d, eta) -> np.ndarray:
    """Chain margins from the IK's leg lengths (independent of the compiled margin)."""
    lengths = leg_lengths(design, Pose(*point, *orientation), np.asarray(d), np.asarray(eta))
    return np.array([leg_margin(design, lengths[i]).min() for i in range(3)])


@pytest.mark.parametrize("design,voxel,orientation", CASES)
def test_neighbour_search_is_within_the_stated_tolerance_of_the_full_search(design, voxel, orientation):
    res = compute_workspace(design, WorkspaceSettings(voxel=voxel, orientation=orientation))
    occ = res.occupancy
    pts = res.grid.points()[occ]
    vals, d, eta, margins = neighbour_field(design, occ, res.grid.axes(), orientation)
    d_full, eta_full = resolved_carriages(design, pts, orientation)
    full_margins = chain_margins(design, pts, d_full, eta_full, orientation)
    # the tolerance (module docstring) at every voxel, not only on a sample
    gap = (full_margins - margins).max(axis=1)
    assert gap.max() <= MARGIN_TOLERANCE
    # the chosen carriage poses lie on the strokes
    lo, hi = design.eta_limits
    assert np.all((d >= -1e-9) & (d <= design.d_s + 1e-9) & (eta >= lo - 1e-9) & (eta <= hi + 1e-9))
    # 1/kappa is eq. (26)'s at the chosen pose (numpy's SVD, the slow path). The kernel's eigenvalues
    # of J J^T lose about kappa^2 1e-16 relative, i.e. kappa 1e-16 absolute: at these off-grid poses
    # one voxel of design1 (1/kappa = 1.7e-6) differs by 1.0e-12, just past the sweep's TOL_ABS
    slow = inverse_condition_batch(design, pts, d, eta, orientation)
    assert np.all(np.abs(vals - slow) <= TOL_REL * slow + TOL_ABS + 1e-16 / np.maximum(slow, 1e-12))
    # the margins reported are the IK's leg margins at the chosen and the full search's poses
    rng = np.random.default_rng(3)
    for k in rng.choice(len(pts), 6, replace=False):
        np.testing.assert_allclose(margins[k], _margins_from_ik(design, pts[k], orientation, d[k], eta[k]), atol=1e-9)
        np.testing.assert_allclose(full_margins[k],
                                   _margins_from_ik(design, pts[k], orientation, d_full[k], eta_full[k]), atol=1e-9)


def test_the_field_reports_its_sample_check_against_the_full_search():
    design, voxel, orientation = CASES[1]
    res = compute_workspace(design, WorkspaceSettings(voxel=voxel, orientation=orientation))
    f = dexterity_field(res, 0.005)
    assert f.search == "neighbour" and f.check is not None
    n = res.voxels
    idx = sample_indices(n)
    assert f.check.sample_size == len(idx) == min(n, max(SAMPLE_MIN, min(SAMPLE_MAX, math.ceil(0.01 * n))))
    # at most SAMPLE_MAX voxels on a large grid, at least SAMPLE_MIN on a small one
    assert len(sample_indices(10**6)) == SAMPLE_MAX == 2000 and len(sample_indices(1000)) == SAMPLE_MIN == 50
    assert len(np.unique(idx)) == len(idx) and np.array_equal(idx, sample_indices(n))  # fixed seed
    # recompute the check's numbers from the full search on the same voxels
    pts = res.grid.points()[res.occupancy][idx]
    d, eta = resolved_carriages(design, pts, orientation)
    full = inverse_condition_batch(design, pts, d, eta, orientation)
    mine = f.inverse_condition[res.occupancy][idx]
    _v, d_nb, eta_nb, _m = neighbour_field(design, res.occupancy, res.grid.axes(), orientation)
    gap = (chain_margins(design, pts, d, eta, orientation)
           - chain_margins(design, pts, d_nb[idx], eta_nb[idx], orientation)).max()
    assert f.check.max_margin_gap == pytest.approx(gap, abs=1e-12)
    # the check takes 1/kappa by the field's compiled eigenvalues, numpy's SVD here: they agree to the
    # sweep's stated tolerance (and kappa 1e-16 absolute, as above)
    tol = float((TOL_REL * full + TOL_ABS + 1e-16 / np.maximum(full, 1e-12)).max())
    assert f.check.max_abs_delta_inverse_condition == pytest.approx(np.abs(mine - full).max(), abs=tol)
    assert f.check.gci_difference == pytest.approx(mine.mean() - full.mean(), abs=tol)
    assert f.check.tolerance_held and f.summary()["dexterity_check"]["tolerance_held"]


def test_a_broken_tolerance_is_reported():
    res = compute_workspace(Design(), WorkspaceSettings(voxel=8.0))
    f = dexterity_field(res, 0.005, margin_tolerance=0.0)
    # on this sample the climb keeps a little less margin than the full search somewhere (0.03)
    assert f.check.max_margin_gap > 0.0
    assert not f.check.tolerance_held and "tolerance broken" in f.check.message
    assert f.summary()["dexterity_check"]["tolerance_held"] is False
    # the comparison itself, on numbers made up for it
    c = compare(np.array([0.5, 0.4]), np.array([[1.0, 2.0, 3.0], [1.0, 1.0, 1.0]]), np.array([0.5, 0.1]),
                np.array([[1.0, 2.5, 3.0], [0.5, 1.0, 1.0]]), 1000, 0.25)
    assert (c.sample_size, c.max_margin_gap, c.max_abs_delta_inverse_condition) == (2, 0.5, pytest.approx(0.3))
    assert c.gci_difference == pytest.approx(0.15) and not c.tolerance_held
    assert compare(np.array([0.5]), np.ones((1, 3)), np.array([0.5]), np.ones((1, 3)), 1, 0.0).tolerance_held


@pytest.mark.parametrize("kw,field", [({"search": "local"}, "dexterity_search"),
                                      ({"margin_tolerance": -1.0}, "margin_tolerance"),
                                      ({"margin_tolerance": float("nan")}, "margin_tolerance"),
                                      ({"margin_tolerance": "x"}, "margin_tolerance")])
def test_search_settings_are_validated(kw, field):
    res = compute_workspace(Design(), WorkspaceSettings(voxel=16.0))
    with pytest.raises(ParameterError, match=field):
        dexterity_field(res, 0.005, **kw)


def _cli(*args: str) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "paraspace.app.cli", *args], capture_output=True, text=True,
                          timeout=600)


def test_cli_reports_the_check_and_a_broken_tolerance():
    proc = _cli("workspace", "--voxel", "8", "--dexterity", "--margin-tolerance", "0", "--json")
    assert proc.returncode == 0, proc.stderr
    chk = json.loads(proc.stdout)["dexterity"]["dexterity_check"]
    assert chk["margin_tolerance"] == 0.0 and chk["tolerance_held"] is False
    assert "paraspace: warning: dexterity tolerance broken" in proc.stderr
    proc = _cli("workspace", "--voxel", "16", "--dexterity", "--dexterity-search", "local", "--json")
    lines = proc.stderr.strip().splitlines()
    assert proc.returncode == 2 and proc.stdout == "" and len(lines) == 1
    assert lines[0].startswith("paraspace: error: dexterity_search = ") and "neighbour or sweep or full" in lines[0]


@pytest.mark.parametrize("design,voxel,orientation", CASES + [(Design(), 5.0, (0.0, 0.0, 0.0))])
def test_the_bounded_restart_scan_gives_the_same_field_as_the_full_scan(design, voxel, orientation):
    # the restart scan pruned by the Lipschitz bounds must take the same restart decisions from the
    # same scan points as the scan of every point: identical arrays, bit for bit
    res = compute_workspace(design, WorkspaceSettings(voxel=voxel, orientation=orientation))
    fast = neighbour_field(design, res.occupancy, res.grid.axes(), orientation)
    ref = neighbour_field(design, res.occupancy, res.grid.axes(), orientation, bounded=False)
    assert res.voxels > 0
    for a, b in zip(fast, ref, strict=True):
        assert np.array_equal(a, b)


def test_the_mirror_searches_the_rows_up_to_y0_and_mirrors_the_poses_of_the_others():
    # the default design at zero orientation is symmetric under y -> -y: the rows up to y = 0 are the
    # search's own (the same arrays as without the mirror), every other voxel gets its mirror voxel's
    # pose mirrored, which the IK and numpy's SVD confirm independently
    design = Design()
    res = compute_workspace(design, WorkspaceSettings(voxel=6.0))
    occ, axes = res.occupancy, res.grid.axes()
    ny_eval = mirror_rows(design, occ, axes, (0.0, 0.0, 0.0))
    assert ny_eval == (occ.shape[1] + 1) // 2
    vals, d, eta, margins = neighbour_field(design, occ, axes)
    plain = neighbour_field(design, occ, axes, mirror=False)
    pts = res.grid.points()[occ]
    j = np.nonzero(occ)[1]
    own = j < ny_eval
    for a, b in zip((vals, d, eta, margins), plain, strict=True):
        assert np.array_equal(a[own], b[own])
    # each mirrored voxel against its mirror image: chains 2 and 3 swapped, eta negated
    index = {tuple(np.round(p, 9)): k for k, p in enumerate(pts)}
    img = np.array([index[tuple(np.round(p * [1.0, -1.0, 1.0], 9))] for p in pts[~own]])
    assert np.array_equal(vals[~own], vals[img])
    assert np.array_equal(d[~own], d[img][:, [0, 2, 1]]) and np.array_equal(eta[~own], -eta[img][:, [0, 2, 1]])
    rng = np.random.default_rng(5)
    for k in rng.choice(np.flatnonzero(~own), 8, replace=False):
        np.testing.assert_allclose(margins[k], _margins_from_ik(design, pts[k], (0.0, 0.0, 0.0), d[k], eta[k]),
                                   atol=1e-9)
    slow = inverse_condition_batch(design, pts[~own], d[~own], eta[~own], (0.0, 0.0, 0.0))
    assert np.all(np.abs(vals[~own] - slow) <= TOL_REL * slow + TOL_ABS + 1e-16 / np.maximum(slow, 1e-12))


@pytest.mark.parametrize("design,orientation,flip", [(Design(eta_range="from-zero"), (0.0, 0.0, 0.0), False),
                                                     (Design(), (0.0, 5.0, 0.0), False),
                                                     (Design(), (0.0, 0.0, 0.0), True)])
def test_no_mirror_where_it_does_not_hold(design, orientation, flip):
    res = compute_workspace(design, WorkspaceSettings(voxel=12.0, orientation=orientation))
    occ = res.occupancy.copy()
    if flip:  # one voxel without its mirror image
        i, j, k = next(v for v in np.argwhere(occ) if v[1] != occ.shape[1] - 1 - v[1])
        occ[i, j, k] = False
    assert mirror_rows(design, occ, res.grid.axes(), orientation) is None


def test_the_field_is_independent_of_the_launches_and_threads(monkeypatch):
    """The planes are launched in runs, in a dealt order (kinematics.slices.dealt_order): neither
    the runs, the order nor the thread count changes a value, and the progress reaches 1 in steps."""
    import numba

    from paraspace.kinematics import dexterity_sweep

    design, voxel, orientation = CASES[1]
    res = compute_workspace(design, WorkspaceSettings(voxel=voxel, orientation=orientation))
    axes = res.grid.axes()
    seen: list[float] = []
    ref = neighbour_field(design, res.occupancy, axes, orientation, progress=lambda f, _m: seen.append(f))
    ref_sweep = dexterity_sweep.continuation_field(design, res.occupancy, axes, orientation)
    assert len(seen) > 1 and seen == sorted(seen) and seen[-1] == 1.0
    for planes in (1, 3):
        monkeypatch.setattr(dexterity_sweep, "PLANES", planes)
        for threads in (1, numba.config.NUMBA_NUM_THREADS):
            numba.set_num_threads(threads)
            try:
                got = neighbour_field(design, res.occupancy, axes, orientation)
                got_sweep = dexterity_sweep.continuation_field(design, res.occupancy, axes, orientation)
            finally:
                numba.set_num_threads(numba.config.NUMBA_NUM_THREADS)
            for a, b in zip(got + got_sweep, ref + ref_sweep):
                assert np.array_equal(a, b), (planes, threads)


@pytest.mark.parametrize("start", sorted({0, _NEAR_START}))  # the levels the field starts from
def test_a_climb_from_either_start_level_ends_at_a_local_maximum_on_the_finest_spacing(start):
    """The climb (from the coarse step or, as a chain that moved little does, from the second level)
    stops where no finest-spacing move in rho, and no finest move in eta with rho re-climbed at the
    finest step, gives more margin; the margin it returns is the margin at its pose. (The climb takes
    the cosine and sine of its steps in eta by the angle-addition formulas, so its margins differ
    from those at math.cos and math.sin by rounding: 1e-9 absolute.)"""
    from paraspace.kinematics import dexterity_neighbour as nb
    from paraspace.kinematics.carriage_search import _NE, _NR, _margin_cs
    from paraspace.kinematics.dexterity_sweep import _constants

    design = Design()
    u, _R2, hb, _inv_L = _constants(design, (0.0, 0.0, 0.0))
    e_lo, e_hi = (math.radians(v) for v in design.eta_limits)
    r_lo, r_hi = design.rho_limits
    se = (e_hi - e_lo) / (_NE - 1) / 25.0
    sr = (r_hi - r_lo) / (_NR - 1) / 25.0
    trig = nb._step_trig(e_lo, e_hi)
    lmin, lmax = float(design.l_min), float(design.l_max)
    res = compute_workspace(design, WorkspaceSettings(voxel=12.0))
    pts = res.grid.points()[res.occupancy]
    rng = np.random.default_rng(5)
    for p in pts[rng.choice(len(pts), 40, replace=False)]:
        for c in range(3):
            g = 2.0 * math.pi * c / 3.0
            b = [*(p + u[c, 0]), *(p + u[c, 1])]
            e0, r0 = rng.uniform(e_lo, e_hi), rng.uniform(r_lo, r_hi)
            r, e, m, cos_e, sin_e = nb._climb(*b, g, e_lo, e_hi, r_lo, r_hi, hb, lmin, lmax, e0, r0, trig, start)
            assert e_lo <= e <= e_hi and r_lo <= r <= r_hi
            cs = math.cos(g + e), math.sin(g + e)
            assert abs(cos_e - cs[0]) <= 1e-12 and abs(sin_e - cs[1]) <= 1e-12  # what 1/kappa takes
            assert m == pytest.approx(_margin_cs(*b, *cs, r, hb, lmin, lmax), abs=1e-9)
            for rr in (min(r + sr, r_hi), max(r - sr, r_lo)):
                assert _margin_cs(*b, *cs, rr, hb, lmin, lmax) <= m + 1e-9
            for ee in (min(e + se, e_hi), max(e - se, e_lo)):
                _r, mm = nb._profile(*b, math.cos(g + ee), math.sin(g + ee), hb, lmin, lmax, r_lo, r_hi, r, sr, 1)
                assert mm <= m + 1e-9
