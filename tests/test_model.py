"""Design validation, rotations (eqs. (2), (7), (27)), joint geometry (eqs. (3)-(5), (11)), mobility (eq. (1))."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.linalg import expm

from paraspace.kinematics.design import PARAMS, Design, ParameterError
from paraspace.kinematics.geometry import base_points, platform_points, platform_points_local
from paraspace.kinematics.jacobian import skew
from paraspace.kinematics.mobility import mobility, topology
from paraspace.kinematics.pose import Pose
from paraspace.kinematics.rotation import Y_PRIME_AXIS, axis_angle, euler_rate_matrix, euler_zyx, euler_zyx_from_matrix


def test_defaults_are_table_one():
    d = Design()
    assert (d.a, d.b, d.d_s, d.r, d.l_min, d.l_s, d.eta_s) == (50, 14, 50, 100, 114.5, 50, 30)
    assert d.l_max == pytest.approx(164.5)
    for name, spec in PARAMS.items():
        assert spec.slider_min <= spec.default <= spec.slider_max, name


@pytest.mark.parametrize("field,value,needle", [
    ("a", -5, "a = -5"), ("d_s", 120, "r=100"), ("eta_s", 500, "180"), ("l_s", float("nan"), "l_s"),
    ("b", "wide", "(a number)"), ("eta_range", "sideways", "centered"),
])
def test_bad_design_names_field_and_range(field, value, needle):
    with pytest.raises(ParameterError) as err:
        Design(**{field: value})
    assert err.value.field == field
    assert needle in str(err.value)
    assert ("valid range" in str(err.value)) or ("expected" in str(err.value))


def test_special_case_strokes_zero_accepted():
    d = Design(d_s=0, eta_s=0)
    assert d.rho_limits == (100.0, 100.0) and d.eta_limits == (0.0, 0.0)


def test_unknown_field_rejected():
    with pytest.raises(ParameterError, match="not a design field"):
        Design.from_dict({"radius": 3})


def test_bad_pose_names_field():
    with pytest.raises(ParameterError, match="theta"):
        Pose(theta=95)


def test_rotation_is_zyx_euler():
    rng = np.random.default_rng(1)
    for _ in range(20):
        psi, theta, phi = rng.uniform(-1.2, 1.2, 3)
        R = euler_zyx(psi, theta, phi)
        assert np.allclose(R @ R.T, np.eye(3)) and np.isclose(np.linalg.det(R), 1.0)
        # composition of elementary rotations, built independently with expm
        ref = expm(skew([0, 0, psi])) @ expm(skew([0, theta, 0])) @ expm(skew([phi, 0, 0]))
        assert np.allclose(R, ref)
        assert np.allclose(euler_zyx_from_matrix(R), (psi, theta, phi))


def test_corrected_rate_matrix_by_finite_differences():
    """omega from R_dot R^T (finite differences) equals R2 [phi', theta', psi'] (corrected eq. (7))."""
    rng = np.random.default_rng(2)
    for _ in range(10):
        ang = rng.uniform(-1.0, 1.0, 3)  # psi, theta, phi
        rates = rng.uniform(-1.0, 1.0, 3)  # phi', theta', psi'
        eps = 1e-6
        dang = np.array([rates[2], rates[1], rates[0]])
        Rp, Rm = euler_zyx(*(ang + eps * dang)), euler_zyx(*(ang - eps * dang))
        W = (Rp - Rm) / (2 * eps) @ euler_zyx(*ang).T
        omega = np.array([W[2, 1], W[0, 2], W[1, 0]])
        assert np.allclose(omega, euler_rate_matrix(ang[0], ang[1]) @ rates, atol=1e-7)
        # the paper's printed R2 has phi where psi belongs: wrong unless phi == psi
        psi, theta, phi = ang
        paper = np.array([[np.cos(theta) * np.cos(phi), -np.sin(phi), 0],
                          [np.cos(theta) * np.sin(phi), np.cos(phi), 0], [-np.sin(theta), 0, 1]])
        assert not np.allclose(omega, paper @ rates, atol=1e-4)


def test_euler_rodrigues_corrected_and_paper_typo():
    rng = np.random.default_rng(3)
    n = Y_PRIME_AXIS
    for tau in rng.uniform(-3, 3, 5):
        R = axis_angle(n, tau)
        assert np.allclose(R, expm(skew(n * tau)))
        c, s = np.cos(tau), np.sin(tau)
        nx, ny, nz = n
        paper = np.array([  # eq. (27) as printed (s_x read as n_x)
            [nx**2 + (1 - nx**2) * c, nx * ny * (1 - c) - nz * s, nx * nz * (1 - c) - ny * s],
            [nx * ny * (1 - c) + nz * s, ny**2 + (1 - ny**2) * c, ny * nz * (1 - c) + nx * s],
            [nx * nz * (1 - c) - ny * s, ny * nz * (1 - c) + nx * s, nz**2 + (1 - nz**2) * c]])
        if abs(s) > 1e-3:
            assert not np.allclose(paper @ paper.T, np.eye(3), atol=1e-6)


def test_platform_and_base_points():
    d = Design(a=37, b=11)
    u = platform_points_local(d).reshape(6, 3)
    assert np.allclose(np.linalg.norm(u, axis=1), 37)
    ang = np.sort(np.degrees(np.arctan2(u[:, 1], u[:, 0])) % 360)
    assert np.allclose(np.diff(ang), 60)  # evenly spaced, at gamma_i -+ 30 deg
    assert np.allclose(ang, [30, 90, 150, 210, 270, 330])
    D = base_points(d, [5, 10, 20], [3, -4, 7])
    assert np.allclose(np.linalg.norm(D[:, 0] - D[:, 1], axis=1), 11)  # |D_i^1 D_i^2| = b
    mid = D.mean(axis=1)
    assert np.allclose(np.linalg.norm(mid, axis=1), [95, 90, 80])  # rho = r - d
    assert np.allclose(np.degrees(np.arctan2(mid[:, 1], mid[:, 0])) % 360, [3, 116, 247])
    B = platform_points(d, [1, 2, 3], euler_zyx(0.1, 0.2, 0.3))
    assert np.allclose(np.linalg.norm(B - [1, 2, 3], axis=-1), 37)


def test_mobility_eq1():
    t = topology()
    assert (t.n, t.g, t.f_sum) == (20, 24, 42)
    assert mobility(t) == 12
    # the numerical check that can fail: tests/test_mobility.py (an independent multibody model)
