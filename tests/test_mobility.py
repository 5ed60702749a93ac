"""Mobility from an independent multibody model (issue 9: the old check, the null-space dimension of
``[J_x, -J_q]``, is 12 for any regular ``J_x`` and cannot fail).

Here every joint of every chain is a variable: per chain the arc angle and the radial slide, per
leg the two U angles, the piston length and the three S angles (XYZ); plus the platform's position
and rotation vector: 48 variables. Each leg closes a loop (base -> carriage -> U -> P -> S ->
platform): position and orientation must match the platform's joint frame, 6 equations per leg,
36 in all. The mobility is ``48 - rank`` of the closure equations' Jacobian (central differences)
at a configuration assembled from the IK. The same model with S joints at BOTH ends of every leg
(S-P-S) must show the six idle leg spins (18), and with a locked carriage (6-UPS) 6, so the count
can fail when the model's joints are wrong.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from paraspace.kinematics.design import Design
from paraspace.kinematics.geometry import GAMMA, LEG_SIGN, platform_points_local
from paraspace.kinematics.mobility import mobility, topology
from paraspace.kinematics.pose import Pose
from paraspace.kinematics.redundancy import resolve_redundancy


def _rx(a):
    return Rotation.from_rotvec([a, 0.0, 0.0]).as_matrix()


def _ry(a):
    return Rotation.from_rotvec([0.0, a, 0.0]).as_matrix()


def _rz(a):
    return Rotation.from_rotvec([0.0, 0.0, a]).as_matrix()


def _leg_frame(design, varpi, rho, j, u1, u2, base_joint):
    """Frame of the piston's base after the joint at D: U (about the carriage's t axis, then the
    rotated e axis) or, for S-P-S, three angles XYZ."""
    c, s = np.cos(varpi), np.sin(varpi)
    lat = LEG_SIGN[j] * design.b / 2.0
    D = np.array([rho * c - lat * s, rho * s + lat * c, 0.0])
    Rc = _rz(varpi)
    if base_joint == "U":
        R = Rc @ _ry(u1[0]) @ _rx(u1[1])
    else:
        R = Rc @ _rx(u1[0]) @ _ry(u1[1]) @ _rz(u2)
    return D, R


def closure(x, design, base_joint="U", lock_carriages=False):
    """Residuals (36,) of the six loops; ``x`` = platform (6) + per chain (varpi, rho) + per leg
    (joint at D: 2 or 3, piston 1, S 3)."""
    p, rv = x[:3], x[3:6]
    Rp = Rotation.from_rotvec(rv).as_matrix()
    u = platform_points_local(design)
    k = 6
    res = []
    for i in range(3):
        varpi, rho = (x[k], x[k + 1]) if not lock_carriages else (GAMMA[i], design.r)
        k += 0 if lock_carriages else 2
        for j in range(2):
            if base_joint == "U":
                ua, extra = x[k:k + 2], 0.0
                k += 2
            else:
                ua, extra = x[k:k + 2], x[k + 2]
                k += 3
            length = x[k]
            s = x[k + 1:k + 4]
            k += 4
            D, R = _leg_frame(design, varpi, rho, j, ua, extra, base_joint)
            B = D + R @ np.array([0.0, 0.0, length])
            Rs = R @ Rotation.from_euler("xyz", s).as_matrix()
            res.append(B - (p + Rp @ u[i, j]))
            res.append(Rotation.from_matrix(Rs.T @ Rp).as_rotvec())
    return np.concatenate(res)


def assemble(design, pose, base_joint="U", lock_carriages=False):
    """A configuration that closes every loop, from the IK (carriages and lengths) and the geometry."""
    sol = resolve_redundancy(design, pose)
    Rp = pose.rotation
    B = (pose.position + platform_points_local(design) @ Rp.T)
    x = list(pose.position) + list(Rotation.from_matrix(Rp).as_rotvec())
    for i in range(3):
        varpi = GAMMA[i] + np.radians(sol.eta[i]) if not lock_carriages else GAMMA[i]
        rho = design.r - sol.d[i] if not lock_carriages else design.r
        if not lock_carriages:
            x += [varpi, rho]
        for j in range(2):
            c, s_ = np.cos(varpi), np.sin(varpi)
            lat = LEG_SIGN[j] * design.b / 2.0
            D = np.array([rho * c - lat * s_, rho * s_ + lat * c, 0.0])
            v = B[i, j] - D
            length = np.linalg.norm(v)
            w = _rz(varpi).T @ (v / length)  # leg direction in the carriage frame
            if base_joint == "U":  # R_y(a) R_x(b) e_z = w
                b = np.arcsin(-w[1])
                a = np.arctan2(w[0], w[2])
                ua, extra = [a, b], None
            else:  # R_x(a) R_y(b) R_z(0) e_z = w
                b = np.arcsin(w[0])
                a = np.arctan2(-w[1], w[2])
                ua, extra = [a, b], 0.0
            _, R = _leg_frame(design, varpi, rho, j, ua, extra or 0.0, base_joint)
            s = Rotation.from_matrix(R.T @ Rp).as_euler("xyz")
            x += ua + ([extra] if base_joint != "U" else []) + [length] + list(s)
    x = np.array(x, float)
    assert np.max(np.abs(closure(x, design, base_joint, lock_carriages))) < 1e-9
    return x


def numeric_mobility(design, pose, base_joint="U", lock_carriages=False) -> int:
    x = assemble(design, pose, base_joint, lock_carriages)
    eps = 1e-6
    J = np.empty((36, x.size))
    for c in range(x.size):
        dx = np.zeros_like(x)
        dx[c] = eps
        J[:, c] = (closure(x + dx, design, base_joint, lock_carriages)
                   - closure(x - dx, design, base_joint, lock_carriages)) / (2 * eps)
    sv = np.linalg.svd(J, compute_uv=False)
    rank = int(np.sum(sv > 1e-7 * sv[0]))
    return x.size - rank


@pytest.mark.parametrize("pose", [Pose(5.0, -3.0, 130.0, 4.0, -2.0, 3.0), Pose(-20.0, 15.0, 150.0, -10.0, 5.0, 8.0)])
def test_mobility_of_the_multibody_model_is_the_papers_count(pose):
    design = Design()
    assert mobility(topology()) == 12
    assert numeric_mobility(design, pose) == 12  # 48 variables, 36 independent closure equations


def test_the_count_can_fail_spinning_legs_and_locked_carriages():
    design = Design()
    pose = Pose(5.0, -3.0, 130.0, 4.0, -2.0, 3.0)
    # S-P-S legs: each leg can spin about its own axis (6 idle DOF): 18
    assert numeric_mobility(design, pose, base_joint="S") == 18
    # carriages locked (a 6-UPS platform): the six pistons only
    assert numeric_mobility(design, pose, lock_carriages=True) == 6
