"""kinematics.line_scan (the orientation scan's coarse-to-fine walk along a line) against the
pair-by-pair test it replaces (kinematics.workspace.reachable_pairs, itself tested against one
reachable() call per orientation in tests/test_workspace.py): identical, pair by pair."""

from __future__ import annotations

import numpy as np
import pytest

from paraspace.kinematics.design import Design
from paraspace.kinematics.joints import Joints
from paraspace.kinematics.line_scan import reachable_along
from paraspace.kinematics.orientation import (
    LINES,
    ROTATIONS,
    OrientationSettings,
    angle_samples,
    line_points,
    orientation_workspace,
    position_samples,
    rotation_matrix,
)
from paraspace.kinematics.workspace import reachable_pairs

SCAN = OrientationSettings(angle_range=80.0, angle_step=2.5, position_step=1.5)

CASES = [
    (Design(), Joints()),
    (Design(eta_range="from-zero"), Joints()),
    (Design(a=70, b=20, l_s=60), Joints(theta_u=45, theta_s=45)),
    (Design(), Joints(theta_u=40, theta_s=50, cone_axis="home")),
    (Design(eta_s=0.0), Joints()),
    (Design(d_s=0, eta_s=0), Joints()),
    (Design(a=35, r=120, l_min=100, l_s=80, eta_s=60), Joints(theta_s=35)),
]


@pytest.mark.parametrize("design,joints", CASES)
def test_identical_to_pairs_on_every_line_and_rotation(design: Design, joints: Joints) -> None:
    feasible = 0
    for line in LINES:
        pts = line_points(line, position_samples(design, line, SCAN), SCAN.z0)
        for rot in ROTATIONS:
            rots = np.stack([rotation_matrix(rot, a) for a in angle_samples(SCAN)])
            fast = reachable_along(design, pts, rots, SCAN.eta_step, joints)
            ref = reachable_pairs(design, pts, rots, SCAN.eta_step, joints)
            assert fast.shape == ref.shape == (len(pts), len(rots))
            assert np.array_equal(fast, ref), f"{line}/{rot}: {(fast != ref).sum()} pairs differ"
            feasible += int(ref.sum())
    assert feasible > 500  # the scan meets the region and its boundary


def test_identical_with_leg_interference() -> None:
    design, joints = Design(), Joints(leg_diameter=12.0, clearance=2.0)
    pts = line_points("z", position_samples(design, "z", SCAN), SCAN.z0)
    rots = np.stack([rotation_matrix("psi_x", a) for a in angle_samples(SCAN)])
    fast = reachable_along(design, pts, rots, SCAN.eta_step, joints)
    ref = reachable_pairs(design, pts, rots, SCAN.eta_step, joints)
    plain = reachable_pairs(design, pts, rots, SCAN.eta_step)
    assert np.array_equal(fast, ref)
    assert (plain & ~ref).any()  # interference removes pairs, so the mask is exercised


@pytest.mark.parametrize("order", ["shuffled", "uneven"])
def test_identical_for_points_not_in_order(order: str) -> None:
    """Correct for any points (only faster along a line): shuffled line points, and a line sampled
    with uneven gaps (runs of very different radii)."""
    design = Design()
    rng = np.random.default_rng(11)
    s = np.linspace(-300.0, 300.0, 401)
    if order == "shuffled":
        s = rng.permutation(s)
    else:
        s = np.sort(rng.uniform(-300.0, 300.0, 401) ** 3 / 300.0 ** 2)
    pts = line_points("x", s, 130.0)
    rots = np.stack([rotation_matrix(rt, a) for rt in ROTATIONS for a in (-50.0, -7.5, 0.0, 21.0, 64.0)])
    fast = reachable_along(design, pts, rots)
    ref = reachable_pairs(design, pts, rots)
    assert np.array_equal(fast, ref)
    assert 0 < ref.sum() < ref.size


def test_scan_grids_are_the_pairwise_test() -> None:
    """orientation_workspace's nine grids are exactly the pair-by-pair test of each line."""
    design = Design(a=60, eta_range="from-zero")
    res = orientation_workspace(design, SCAN)
    for (line, rot), reg in res.regions.items():
        rots = np.stack([rotation_matrix(rot, a) for a in reg.angles])
        ref = reachable_pairs(design, line_points(line, reg.positions, SCAN.z0), rots, SCAN.eta_step)
        assert np.array_equal(reg.feasible, ref), (line, rot)


def test_empty_inputs() -> None:
    d = Design()
    assert reachable_along(d, np.zeros((0, 3)), np.eye(3)[None]).shape == (0, 1)
    assert reachable_along(d, np.zeros((4, 3)), np.zeros((0, 3, 3))).shape == (4, 0)
