"""Jacobians (eqs. (17)-(26)) against finite differences of our IK; IK/FK round trips; redundancy resolution."""

from __future__ import annotations

import numpy as np
import pytest

from paraspace.kinematics.design import Design, ParameterError
from paraspace.kinematics.forward import forward_kinematics
from paraspace.kinematics.geometry import GAMMA, LEG_SIGN
from paraspace.kinematics.inverse import leg_lengths
from paraspace.kinematics.jacobian import jacobians
from paraspace.kinematics.pose import Pose
from paraspace.kinematics.redundancy import inverse_kinematics, resolve_redundancy
from paraspace.kinematics.workspace import reachable

DESIGN = Design()


def _poses(n, seed=0):
    rng = np.random.default_rng(seed)
    for _ in range(n):
        yield Pose(*rng.uniform(-25, 25, 2), rng.uniform(120, 145), *rng.uniform(-8, 8, 3))


def _lengths_from_vec(v, d, eta):  # v = [x, y, z, phi, theta, psi] (rad)
    return leg_lengths(DESIGN, Pose(v[0], v[1], v[2], np.degrees(v[5]), np.degrees(v[4]), np.degrees(v[3])),
                       d, eta).reshape(6)


def test_jacobians_match_finite_differences():
    rng = np.random.default_rng(5)
    for pose in _poses(6):
        d, eta = rng.uniform(0, 50, 3), rng.uniform(-15, 15, 3)
        J = jacobians(DESIGN, pose, d, eta)
        v = np.array([pose.x, pose.y, pose.z, np.radians(pose.phi), np.radians(pose.theta), np.radians(pose.psi)])
        eps = 1e-6
        # dl/dx at fixed carriage = J_x (since l_dot = J_x x_dot - E d_dot - F eta_dot)
        fd = np.column_stack([(_lengths_from_vec(v + eps * e, d, eta) - _lengths_from_vec(v - eps * e, d, eta))
                              / (2 * eps) for e in np.eye(6)])
        assert np.allclose(fd, J.J_x, atol=1e-6)
        # dl/dd_i = -e and dl/deta_i (per radian) = -f
        for i in range(3):
            dp, dm = d.copy(), d.copy()
            dp[i] += eps
            dm[i] -= eps
            col = (leg_lengths(DESIGN, pose, dp, eta) - leg_lengths(DESIGN, pose, dm, eta)).reshape(6) / (2 * eps)
            assert np.allclose(col, -J.J_q[:, 6 + i], atol=1e-6)
            ep, em = eta.copy(), eta.copy()
            ep[i] += np.degrees(eps)
            em[i] -= np.degrees(eps)
            col = (leg_lengths(DESIGN, pose, d, ep) - leg_lengths(DESIGN, pose, d, em)).reshape(6) / (2 * eps)
            assert np.allclose(col, -J.J_q[:, 9 + i], atol=1e-5)
        assert np.allclose(J.J_q[:, :6], np.eye(6))
        L = DESIGN.a / 2
        assert np.allclose(J.J_h[:, 3:] * L, J.J_x[:, 3:])
        assert np.allclose(J.J_h @ J.J, J.J_q)
        s = np.linalg.svd(J.J, compute_uv=False)
        assert J.condition_number == pytest.approx(s[0] / s[-1])


def test_paper_t_vector_typo_fails_finite_differences():
    """Eq. (14) as printed ((r-d) sin in the 2nd component) disagrees with dD/deta."""
    pose, d, eta = Pose(10, 5, 130), np.array([10.0, 20, 30]), np.array([5.0, -3, 8])
    J = jacobians(DESIGN, pose, d, eta)
    varpi = np.radians(eta) + GAMMA
    i, j = 0, 0
    lat = LEG_SIGN[j] * DESIGN.b / 2
    t_paper = np.array([(d[i] - DESIGN.r) * np.sin(varpi[i]) - lat * np.cos(varpi[i]),
                        (DESIGN.r - d[i]) * np.sin(varpi[i]) - lat * np.sin(varpi[i]), 0.0])
    # s from the J_x row: its first three entries are s^T
    f_paper = J.J_x[0, :3] @ t_paper
    assert not np.isclose(f_paper, J.J_q[0, 9], atol=1e-3)


def test_ik_fk_round_trip():
    for pose in _poses(10, seed=1):
        res = resolve_redundancy(DESIGN, pose)
        assert res.feasible, res.message
        start = Pose(pose.x + 3, pose.y - 2, pose.z + 4, pose.psi + 2, pose.theta - 1, pose.phi + 1)
        fk = forward_kinematics(DESIGN, res.lengths, res.d, res.eta, initial=start)
        assert fk.converged and fk.residual < 1e-8
        assert np.allclose(fk.pose.as_array(), pose.as_array(), atol=1e-6)


def test_resolution_maximises_margin_against_random_search():
    rng = np.random.default_rng(9)
    for pose in _poses(4, seed=2):
        res = resolve_redundancy(DESIGN, pose)
        d = rng.uniform(0, DESIGN.d_s, (4000, 3))
        eta = rng.uniform(*DESIGN.eta_limits, (4000, 3))
        for i in range(3):
            best_random = -np.inf
            for k in range(4000):
                l = leg_lengths(DESIGN, pose, d[k], eta[k])[i]
                best_random = max(best_random, np.minimum(l - DESIGN.l_min, DESIGN.l_max - l).min())
            assert res.chains[i].margin >= best_random - 1e-3


def test_resolution_agrees_with_workspace_test_and_names_failure():
    rng = np.random.default_rng(4)
    pts = np.column_stack([rng.uniform(-150, 150, 300), rng.uniform(-150, 150, 300), rng.uniform(60, 170, 300)])
    inside = reachable(DESIGN, pts, eta_step=0.25)
    agree = 0
    for p, ok in zip(pts, inside):
        res = resolve_redundancy(DESIGN, Pose(*p))
        agree += res.feasible == ok
        if not res.feasible:
            assert res.message.startswith("unreachable: chain ")
            assert ("too long" in res.message) or ("too short" in res.message)
            bad = [c for c in res.chains if not c.feasible]
            assert all(any(s in ("too_long", "too_short") for s in c.leg_status) for c in bad)
    assert agree >= 297  # disagreements only within the sampling error at the boundary


def test_manual_carriage_validated_and_reported():
    with pytest.raises(ParameterError, match="d_2"):
        inverse_kinematics(DESIGN, Pose(), [0, 60, 0], [0, 0, 0])
    with pytest.raises(ParameterError, match="eta_3"):
        inverse_kinematics(DESIGN, Pose(), [0, 0, 0], [0, 0, 20])
    res = inverse_kinematics(DESIGN, Pose(0, 0, 130), [0, 0, 0], [0, 0, 0])
    assert np.allclose(res.lengths, leg_lengths(DESIGN, Pose(0, 0, 130), [0] * 3, [0] * 3))
    assert res.mode == "manual"
