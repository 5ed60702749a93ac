"""The resolver's full search bounded by blocks (kinematics/carriage_search.py): the same carriage
poses as the scan of every grid point, bit for bit, on designs whose strokes, arcs and orientations
differ (a zero stroke included); the bound it rests on, checked on random carriage poses with the
IK's leg lengths; and the coarse grid's maximiser against numpy's argmax of the IK's margins."""

from __future__ import annotations

import math

import numpy as np
import pytest

from paraspace.kinematics.carriage_search import _NE, _NR, bounded_argmax, work_arrays
from paraspace.kinematics.design import Design
from paraspace.kinematics.dexterity import resolved_carriages
from paraspace.kinematics.dexterity_sweep import _constants
from paraspace.kinematics.inverse import leg_lengths, leg_margin
from paraspace.kinematics.pose import Pose
from paraspace.kinematics.workspace import WorkspaceSettings, compute_workspace

CASES = [(Design(), (0.0, 0.0, 0.0)),
         (Design(a=30, b=20, eta_s=60), (8.0, -5.0, 3.0)),
         (Design(d_s=80, eta_s=45), (0.0, 0.0, 0.0)),
         (Design(a=80, eta_range="from-zero"), (0.0, 10.0, 0.0)),
         (Design(eta_s=0), (0.0, 0.0, 0.0)),
         (Design(d_s=0), (5.0, 0.0, -5.0))]


def _points(design: Design, orientation, n_random: int = 300) -> np.ndarray:
    """The reachable voxels of a coarse workspace and random positions about it (reachable or not)."""
    res = compute_workspace(design, WorkspaceSettings(voxel=10.0, orientation=orientation))
    rng = np.random.default_rng(int(design.a + design.eta_s))
    extra = np.column_stack([rng.uniform(-120, 120, n_random), rng.uniform(-120, 120, n_random),
                             rng.uniform(40, 260, n_random)])
    return np.vstack([res.grid.points()[res.occupancy], extra])


@pytest.mark.parametrize("design,orientation", CASES)
def test_the_bounded_search_gives_the_full_searchs_poses_bit_for_bit(design, orientation):
    pts = _points(design, orientation)
    d, eta = resolved_carriages(design, pts, orientation)
    d_ref, eta_ref = resolved_carriages(design, pts, orientation, bounded=False)
    assert pts.shape[0] > 300
    assert np.array_equal(d, d_ref) and np.array_equal(eta, eta_ref)


def _chain_margin(design: Design, pose: Pose, chain: int, d: float, eta_deg: float) -> float:
    """Chain ``chain``'s margin from the IK's leg lengths (the other chains at mid-stroke)."""
    dd = np.full(3, 0.5 * design.d_s)
    ee = np.full(3, 0.5 * sum(design.eta_limits))
    dd[chain], ee[chain] = d, eta_deg
    return float(leg_margin(design, leg_lengths(design, pose, dd, ee)[chain]).min())


def test_the_margin_moves_no_more_than_the_bound_says():
    # |m(eta, rho) - m(eta', rho')| <= |rho - rho'| + sqrt(R^2 + (b/2)^2) |eta - eta'|, R the larger
    # |rho|: the bound that lets a block be left out
    design = Design(a=30, b=20, eta_s=60)
    rng = np.random.default_rng(3)
    e_lo, e_hi = design.eta_limits
    hb = 0.5 * design.b
    worst = 0.0
    for _ in range(400):
        pose = Pose(rng.uniform(-40, 40), rng.uniform(-40, 40), rng.uniform(90, 160), *rng.uniform(-10, 10, 3))
        chain = int(rng.integers(3))
        d0, d1 = rng.uniform(0, design.d_s, 2)
        e0, e1 = rng.uniform(e_lo, e_hi, 2)
        r0, r1 = design.r - d0, design.r - d1
        change = abs(_chain_margin(design, pose, chain, d0, e0) - _chain_margin(design, pose, chain, d1, e1))
        bound = abs(r0 - r1) + math.hypot(max(abs(r0), abs(r1)), hb) * abs(math.radians(e0 - e1))
        assert change <= bound + 1e-9
        worst = max(worst, change / bound)
    assert worst > 0.5  # the bound is not loose everywhere


@pytest.mark.parametrize("design,orientation", CASES[:3])
def test_the_coarse_maximiser_is_numpys_argmax_of_the_ik_margins(design, orientation):
    u, _R2, hb, _ = _constants(design, orientation)
    e_lo, e_hi = (math.radians(v) for v in design.eta_limits)
    r_lo, r_hi = design.rho_limits
    etas, rhos = np.linspace(e_lo, e_hi, _NE), np.linspace(r_lo, r_hi, _NR)
    CS, UB = work_arrays()
    rng = np.random.default_rng(11)
    pts = _points(design, orientation, 0)
    for p in pts[rng.choice(len(pts), 3, replace=False)]:
        pose = Pose(*p, *orientation)
        for chain in range(3):
            ke, kr = bounded_argmax(*(p + u[chain, 0]), *(p + u[chain, 1]), 2.0 * math.pi * chain / 3.0,
                                    e_lo, e_hi, _NE, r_lo, r_hi, _NR, hb, design.l_min, design.l_max, CS, UB)
            grid = np.array([[_chain_margin(design, pose, chain, design.r - r, math.degrees(e)) for r in rhos]
                             for e in etas])
            assert grid[ke, kr] == pytest.approx(grid.max(), abs=1e-9)
