"""Dexterity (issue 9): 1/kappa of eq. (26) against numpy's cond of a finite-difference Jacobian
built only from the IK (leg lengths), the field, GCI and the well-conditioned workspace."""

from __future__ import annotations

import itertools
import json
import subprocess
import sys

import numpy as np
import pytest

from paraspace.kinematics.design import Design, ParameterError
from paraspace.kinematics.dexterity import carriage_samples, dexterity_at, dexterity_field, resolved_carriages
from paraspace.kinematics.inverse import leg_lengths, leg_margin
from paraspace.kinematics.pose import Pose
from paraspace.kinematics.redundancy import resolve_redundancy
from paraspace.kinematics.workspace import WorkspaceSettings, compute_workspace

DESIGN = Design()


def fd_inverse_condition(design: Design, pose: Pose, d, eta_deg, step: float = 1e-6) -> float:
    """1/cond(J) with J = J_h^{-1} J_q from central differences of the leg lengths g(x, d, eta):
    the closure l = g gives J_x = dg/dx (x = [P, phi, theta, psi], radians) and
    J_q = [I | -dg/dd | -dg/deta (per radian)]; J_h scales J_x's angular columns by 1/L, L = a/2."""
    x0 = np.array([pose.x, pose.y, pose.z, np.radians(pose.phi), np.radians(pose.theta), np.radians(pose.psi)])
    d = np.asarray(d, float)
    eta = np.radians(np.asarray(eta_deg, float))

    def g(x, dd, ee):
        p = Pose(x[0], x[1], x[2], np.degrees(x[5]), np.degrees(x[4]), np.degrees(x[3]))
        return leg_lengths(design, p, dd, np.degrees(ee)).reshape(6)

    J_x = np.zeros((6, 6))
    for k in range(6):
        e = np.zeros(6)
        e[k] = step
        J_x[:, k] = (g(x0 + e, d, eta) - g(x0 - e, d, eta)) / (2 * step)
    J_q = np.zeros((6, 12))
    J_q[:, :6] = np.eye(6)
    for i in range(3):
        e = np.zeros(3)
        e[i] = step
        J_q[:, 6 + i] = -(g(x0, d + e, eta) - g(x0, d - e, eta)) / (2 * step)
        J_q[:, 9 + i] = -(g(x0, d, eta + e) - g(x0, d, eta - e)) / (2 * step)
    L = design.a / 2.0
    J_h = np.hstack([J_x[:, :3], J_x[:, 3:] / L])
    return 1.0 / np.linalg.cond(np.linalg.solve(J_h, J_q))


def random_poses(n: int, seed: int = 0, rot: float = 12.0) -> list[Pose]:
    rng = np.random.default_rng(seed)
    return [Pose(rng.uniform(-35, 35), rng.uniform(-35, 35), rng.uniform(95, 155),
                 rng.uniform(-rot, rot), rng.uniform(-rot, rot), rng.uniform(-rot, rot)) for _ in range(n)]


@pytest.mark.parametrize("design", [DESIGN, Design(a=30, b=20, eta_s=60), Design(a=80, eta_range="from-zero")])
def test_inverse_condition_matches_finite_difference_cond(design):
    for pose in random_poses(8, seed=int(design.a)):
        dex = dexterity_at(design, pose)
        ref = fd_inverse_condition(design, pose, dex.d, dex.eta)
        assert dex.inverse_condition == pytest.approx(ref, rel=1e-5)
        assert 0.0 < dex.inverse_condition <= 1.0


def test_resolved_carriages_are_the_resolvers():
    poses = random_poses(20, seed=3)
    for orient in [(0.0, 0.0, 0.0), (10.0, -5.0, 7.0)]:
        pts = np.array([[p.x, p.y, p.z] for p in poses])
        d, eta = resolved_carriages(DESIGN, pts, orient)
        for k, p in enumerate(pts):
            pose = Pose(*p, *orient)
            res = resolve_redundancy(DESIGN, pose)
            mine = leg_margin(DESIGN, leg_lengths(DESIGN, pose, d[k], eta[k])).min(axis=1)
            theirs = np.array([c.margin for c in res.chains])
            np.testing.assert_allclose(mine, theirs, atol=1e-9)
            np.testing.assert_allclose(d[k], res.d, atol=1e-6)
            np.testing.assert_allclose(eta[k], res.eta, atol=1e-6)


@pytest.fixture(scope="module")
def coarse():
    return compute_workspace(DESIGN, WorkspaceSettings(voxel=8.0))


def test_field_gci_and_well_conditioned_workspace(coarse):
    # the resolver's exact carriage poses (search="sweep"); the default neighbour search's are
    # within a margin tolerance of them (tests/test_dexterity_neighbour.py)
    f = dexterity_field(coarse, kappa_min=0.004, search="sweep")
    occ = coarse.occupancy
    assert np.all(np.isfinite(f.inverse_condition[occ])) and np.all(np.isnan(f.inverse_condition[~occ]))
    # spot-check voxels against the finite-difference oracle at the resolver's carriage pose
    pts = coarse.grid.points()
    idx = np.argwhere(occ)
    rng = np.random.default_rng(1)
    for k in rng.choice(len(idx), 12, replace=False):
        i, j, l = idx[k]
        pose = Pose(*pts[i, j, l])
        res = resolve_redundancy(DESIGN, pose)
        assert f.inverse_condition[i, j, l] == pytest.approx(fd_inverse_condition(DESIGN, pose, res.d, res.eta),
                                                             rel=1e-5)
    vals = f.inverse_condition[occ]
    assert f.gci == pytest.approx(vals.mean())
    assert np.array_equal(f.well_conditioned, occ & (np.nan_to_num(f.inverse_condition) >= 0.004))
    assert f.well_conditioned_volume == pytest.approx(f.well_conditioned.sum() * 8.0 ** 3)
    assert 0 < f.well_conditioned_volume < coarse.volume
    wr = f.well_conditioned_result(coarse)
    assert wr.volume == pytest.approx(f.well_conditioned_volume) and wr.grid == coarse.grid
    # a higher threshold only removes voxels
    g = dexterity_field(coarse, kappa_min=0.006, search="sweep")
    assert not np.any(g.well_conditioned & ~f.well_conditioned)
    assert g.gci == pytest.approx(f.gci)


def test_best_is_at_least_resolved_and_exhaustive_is_the_true_max():
    pose = Pose(10.0, -15.0, 125.0, 5.0, 0.0, -4.0)
    coord = dexterity_at(DESIGN, pose, "best", n_eta=3, n_d=2)
    exh = dexterity_at(DESIGN, pose, "best", n_eta=3, n_d=2, search="exhaustive")
    assert coord.inverse_condition >= coord.resolved - 1e-15
    assert exh.inverse_condition >= coord.inverse_condition - 1e-12
    # independent brute force: every feasible combination of the per-chain samples (plus the resolved one)
    res = resolve_redundancy(DESIGN, pose)
    ds, es = carriage_samples(DESIGN, 3, 2)
    per_chain = []
    for i in range(3):
        cand = [(float(res.d[i]), float(res.eta[i]))]
        for dv, ev in zip(ds, es):
            dd, ee = res.d.copy(), res.eta.copy()
            dd[i], ee[i] = dv, ev
            lengths = leg_lengths(DESIGN, pose, dd, ee)[i]
            if np.all((lengths >= DESIGN.l_min - 1e-9) & (lengths <= DESIGN.l_max + 1e-9)):
                cand.append((float(dv), float(ev)))
        per_chain.append(cand)
    best = max(fd_inverse_condition(DESIGN, pose, [c[0] for c in combo], [c[1] for c in combo])
               for combo in itertools.product(*per_chain))
    assert exh.inverse_condition == pytest.approx(best, rel=1e-5)
    # the carriage pose it reports is feasible and gives its value
    lengths = leg_lengths(DESIGN, pose, exh.d, exh.eta)
    assert np.all(leg_margin(DESIGN, lengths) >= -1e-9)
    assert fd_inverse_condition(DESIGN, pose, exh.d, exh.eta) == pytest.approx(exh.inverse_condition, rel=1e-5)


def test_best_field_dominates_resolved_field():
    res = compute_workspace(DESIGN, WorkspaceSettings(voxel=16.0))
    # mode="best" starts from the full search's 1/kappa (numpy's SVD); the default sweep's agrees
    # with it to TOL_REL (test_sweep_field_is_the_full_search), not to the last bit
    r = dexterity_field(res, 0.005, search="full")
    b = dexterity_field(res, 0.005, mode="best", n_eta=3, n_d=2, sweeps=1)
    occ = res.occupancy
    assert np.all(b.inverse_condition[occ] >= r.inverse_condition[occ] - 1e-15)
    assert b.gci >= r.gci and b.well_conditioned_volume >= r.well_conditioned_volume


@pytest.mark.parametrize("bad", [0.0, -0.1, 1.5, float("nan"), "x"])
def test_kappa_min_is_validated(coarse, bad):
    with pytest.raises(ParameterError, match="kappa_min"):
        dexterity_field(coarse, kappa_min=bad)


def test_mode_is_validated(coarse):
    with pytest.raises(ParameterError, match="mode"):
        dexterity_field(coarse, mode="worst")


def cli(*args: str) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "paraspace.app.cli", *args], capture_output=True, text=True,
                          timeout=300)


def test_cli_workspace_dexterity_json():
    proc = cli("workspace", "--voxel", "8", "--dexterity", "--kappa-min", "0.004", "--json")
    assert proc.returncode == 0, proc.stderr
    out = json.loads(proc.stdout)
    ref = dexterity_field(compute_workspace(DESIGN, WorkspaceSettings(voxel=8.0)), 0.004)
    assert out["gci"] == pytest.approx(ref.gci)
    assert out["well_conditioned_volume"] == pytest.approx(ref.well_conditioned_volume)
    assert out["kappa_min"] == 0.004 and out["dexterity"]["dexterity_mode"] == "resolved"


@pytest.mark.parametrize("args,field,valid", [(("--kappa-min", "0"), "kappa_min", "(0, 1]"),
                                              (("--kappa-min", "abc"), "kappa_min", "(0, 1]"),
                                              (("--dexterity", "--dexterity-mode", "worst"), "dexterity_mode",
                                               "resolved or best")])
def test_cli_dexterity_bad_input(args, field, valid):
    proc = cli("workspace", "--voxel", "8", *args, "--json")
    assert proc.returncode == 2 and proc.stdout == ""
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith(f"paraspace: error: {field} = ") and valid in lines[0]


@pytest.mark.parametrize("design,voxel,orientation", [(DESIGN, 8.0, (0.0, 0.0, 0.0)),
                                                      (Design(a=30, b=20, eta_s=60), 10.0, (8.0, -5.0, 3.0))])
def test_sweep_field_is_the_full_search(design, voxel, orientation):
    """Issue 24 target 3: the pruned sweep (kinematics/dexterity_sweep.py, search="sweep") finds the
    resolver's full-search carriage poses bit for bit and 1/kappa within the stated tolerance of
    numpy's SVD at every voxel, also where 1/kappa is about 1e-5 (the slow path: resolved_carriages
    and inverse_condition_batch)."""
    from paraspace.kinematics.dexterity import inverse_condition_batch
    from paraspace.kinematics.dexterity_sweep import TOL_ABS, TOL_REL, continuation_field

    res = compute_workspace(design, WorkspaceSettings(voxel=voxel, orientation=orientation))
    occ = res.occupancy
    pts = res.grid.points()[occ]
    vals, d, eta = continuation_field(design, occ, res.grid.axes(), orientation)
    d_full, eta_full = resolved_carriages(design, pts, orientation)
    assert np.array_equal(d, d_full) and np.array_equal(eta, eta_full)
    full = inverse_condition_batch(design, pts, d_full, eta_full, orientation)
    assert np.all(np.abs(vals - full) <= TOL_REL * full + TOL_ABS)
    f = dexterity_field(res, 0.005, search="sweep")
    g = dexterity_field(res, 0.005, search="full")
    np.testing.assert_array_equal(f.inverse_condition[occ], vals)
    np.testing.assert_allclose(f.inverse_condition[occ], g.inverse_condition[occ], rtol=TOL_REL, atol=TOL_ABS)
    with pytest.raises(ParameterError, match="search"):
        dexterity_field(res, 0.005, search="local")
    # 1/kappa at given poses (the neighbour search's check) by the compiled eigenvalues: the sweep's
    # numbers at its poses (to the rounding of d = r - rho and of degrees), and within the tolerance
    # of the SVD at random poses
    from paraspace.kinematics.dexterity_sweep import inverse_condition_at

    at = inverse_condition_at(design, pts, d, eta, orientation)
    assert np.all(np.abs(at - vals) <= TOL_REL * vals + TOL_ABS + 1e-16 / np.maximum(vals, 1e-12))
    assert np.median(np.abs(at - vals) / vals) < 1e-12
    rng = np.random.default_rng(11)
    k = rng.choice(len(pts), min(300, len(pts)), replace=False)
    lo, hi = design.eta_limits
    d_r = rng.uniform(0.0, design.d_s, (k.size, 3))
    e_r = rng.uniform(lo, hi, (k.size, 3))
    at = inverse_condition_at(design, pts[k], d_r, e_r, orientation)
    svd = inverse_condition_batch(design, pts[k], d_r, e_r, orientation)
    assert np.all(np.abs(at - svd) <= TOL_REL * svd + TOL_ABS + 1e-16 / np.maximum(svd, 1e-12))
    assert inverse_condition_at(design, np.zeros((0, 3)), np.zeros((0, 3)), np.zeros((0, 3))).shape == (0,)


def _spectra(rng):
    """6 x 6 symmetric positive semidefinite matrices with spectra that are hard for an eigenvalue
    iteration: spread over 1e-7 .. 1, repeated extremes (double, triple, all equal), a cluster at
    either end, rank deficient, diagonal and already tridiagonal, and random Gram matrices."""
    specs = [rng.uniform(0.01, 1.0, 6), np.logspace(-7, 0, 6), np.array([1, 1, 0.5, 0.3, 0.1, 0.01]),
             np.array([1, 0.5, 0.3, 0.1, 0.01, 0.01]), np.array([2, 2, 2, 1e-3, 1e-3, 1e-3]), np.full(6, 0.7),
             np.array([1, 1 - 1e-9, 0.5, 0.2, 1e-6, 1e-6 * (1 + 1e-9)]), np.array([1, 0.5, 0.4, 0.2, 0.1, 0.0]),
             np.array([3.0, 0, 0, 0, 0, 0])]
    out = []
    for lam in specs:
        q, _ = np.linalg.qr(rng.normal(size=(6, 6)))
        out += [(q * lam) @ q.T, np.diag(rng.permutation(lam))]
        t = np.diag(lam) + np.diag(np.full(5, 0.1 * lam.max()), 1) + np.diag(np.full(5, 0.1 * lam.max()), -1)
        out.append(t + 0.3 * lam.max() * np.eye(6))
    for _ in range(40):
        m = rng.normal(size=(6, 6)) * rng.uniform(0.1, 10.0)
        out.append(m.T @ m)
    return out


def test_extreme_eigenvalues_of_the_kernel_are_numpys():
    """The compiled 1/kappa's eigenvalue step (Householder, then Laguerre from outside the spectrum:
    kinematics/dexterity_sweep._tridiagonal_eigen_range) against numpy's eigvalsh: it converges, also
    on repeated and clustered extremes, and both extreme eigenvalues are within a few eps of the
    largest (5 eps measured)."""
    from paraspace.kinematics.dexterity_sweep import _tridiagonal_eigen_range

    rng = np.random.default_rng(11)
    for g in _spectra(rng):
        g = (g + g.T) / 2
        ref = np.linalg.eigvalsh(g)
        lo, hi, ok = _tridiagonal_eigen_range(g.copy(), np.zeros((6, 18)))
        assert ok, ref
        scale = ref[-1]
        assert abs(hi - ref[-1]) <= 20 * 2.2e-16 * scale, (ref, hi)
        assert abs(lo - ref[0]) <= 20 * 2.2e-16 * scale, (ref, lo)
